/**
 * The vibration actuators (A1..A9) as a heat map, one row each. Per pixel column the row shows
 * the strongest value in the column's ticks (max pyramid), written into a width x 9 image that is
 * scaled onto the lane without smoothing.
 */

import { HEAT_LUT } from "../core/colormap.js";
import { BaseLane, background, message } from "./common.js";

const ROW_H = 15;

/**
 * @typedef {{data: () => import("../data/timeline-data.js").TimelineData|null,
 *   actuators: import("../data/layout.js").ActuatorInfo[]}} ActuatorsHooks the actuators in the timeline's order
 */

/** @extends {BaseLane<ActuatorsHooks>} */
export class ActuatorsLane extends BaseLane {
  /** @param {ActuatorsHooks} hooks */
  constructor(hooks) {
    const ids = hooks.actuators.map((a) => a.id);
    const title = `Vibration ${ids[0]}..${ids[ids.length - 1]} as a heat map (dark = off, yellow = full); drag across rows to select them`;
    super({ id: "actuators", label: "Vibration", title, height: ROW_H * ids.length }, hooks);
    this.ids = ids;
    /** @type {ImageData|null} */
    this.image = null;
    this.scratch = document.createElement("canvas");
    this.scratchCtx = /** @type {CanvasRenderingContext2D} */ (this.scratch.getContext("2d"));
  }

  /** @param {number} height */
  editRows(height) {
    const h = height / this.ids.length;
    return this.ids.map((lane, i) => ({ lane, y0: i * h, y1: (i + 1) * h }));
  }

  /** @param {HTMLElement} label */
  decorateLabel(label) {
    const list = document.createElement("div");
    list.className = "tl-sublabels";
    for (const a of this.hooks.actuators) {
      const s = document.createElement("span");
      s.textContent = a.id;
      const zone = a.body || a.zone;
      if (zone) s.title = `${a.id}: ${zone}`;
      list.append(s);
    }
    label.classList.add("tl-label-rows");
    label.append(list);
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").LaneFrame} f
   */
  draw(ctx, { width, height, view }) {
    background(ctx, width, height);
    const data = this.hooks.data();
    if (!data) {
      message(ctx, width, height, "");
      return;
    }
    const rows = this.ids.length;
    if (!this.image || this.image.width !== width) {
      this.image = new ImageData(width, rows);
      this.scratch.width = width;
      this.scratch.height = rows;
    }
    const words = new Uint32Array(this.image.data.buffer);
    const bg = HEAT_LUT[0];
    for (let a = 0; a < rows; a++) {
      const { max } = this.cols.fill(data.vibrationPyr[a], view, width, 1 / data.tickS);
      const row = a * width;
      for (let x = 0; x < width; x++) {
        const v = max[x];
        words[row + x] = Number.isNaN(v) ? bg : HEAT_LUT[v];
      }
    }
    this.scratchCtx.putImageData(this.image, 0, 0);
    ctx.save();
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(this.scratch, 0, 0, width, rows, 0, 0, width, height);
    ctx.restore();
    ctx.strokeStyle = "rgba(0, 0, 0, 0.55)";
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let a = 1; a < rows; a++) {
      const y = Math.round((a * height) / rows) + 0.5;
      ctx.moveTo(0, y);
      ctx.lineTo(width, y);
    }
    ctx.stroke();
  }
}
