/**
 * Fan activity: the fraction of the 17 x 9 fans that are on, per tick (the grid itself is drawn
 * over the video at the playhead by ../fan-overlay.js).
 */

import { COLORS } from "../core/colormap.js";
import { Columns, areaPath, background, message } from "./common.js";

export class FansLane {
  /** @param {{data: () => import("../data/timeline-data.js").TimelineData|null}} hooks */
  constructor(hooks) {
    this.id = "fans";
    this.label = "Fans";
    this.title = "Airflow: fraction of the 17 x 9 fans that are on";
    this.height = 40;
    this.hooks = hooks;
    this.cols = new Columns();
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
