/**
 * Fan activity: the fraction of the fans (17 x 9 on the chair) that are on, per tick (the grid itself is drawn
 * over the video at the playhead by ../chair/fan-overlay.js).
 */

import { COLORS } from "../core/colormap.js";
import { BaseLane, areaPath, background, message } from "./common.js";

/** @typedef {{data: () => import("../data/timeline-data.js").TimelineData|null, grid: {rows: number, cols: number}}} FansHooks */

/** @extends {BaseLane<FansHooks>} */
export class FansLane extends BaseLane {
  /** @param {FansHooks} hooks */
  constructor(hooks) {
    const { rows, cols } = hooks.grid;
    super({ id: "fans", label: "Fans", title: `Airflow: fraction of the ${cols} x ${rows} fans that are on`, height: 40 }, hooks);
  }

  /** @param {number} height */
  editRows(height) {
    return [{ lane: "fans", y0: 0, y1: height }];
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").LaneFrame} f
   */
  draw(ctx, { width, height, view }) {
    background(ctx, width, height, [0.5]);
    const data = this.hooks.data();
    if (!data) {
      message(ctx, width, height, "");
      return;
    }
    const { max } = this.cols.fill(data.fanActivityPyr, view, width, 1 / data.tickS);
    areaPath(ctx, max, width, 3, height - 2, 255);
    ctx.fillStyle = "rgba(103, 232, 249, 0.45)";
    ctx.fill();
    ctx.strokeStyle = COLORS.fans;
    ctx.lineWidth = 1;
    ctx.stroke();
  }
}
