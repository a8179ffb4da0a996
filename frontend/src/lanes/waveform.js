/**
 * The audio waveform lane: peaks computed by the server (GET /waveform), drawn per pixel column
 * from a min/max pyramid.
 */

import { COLORS } from "../core/colormap.js";
import { MinMaxPyramid } from "../data/pyramid.js";
import { BaseLane, background, message } from "./common.js";

/** @extends {BaseLane<null>} */
export class WaveformLane extends BaseLane {
  /** @param {{height?: number}} [opts] */
  constructor(opts = {}) {
    super({ id: "waveform", label: "Audio", title: "Audio waveform (peaks computed by the server)", height: opts.height ?? 56 }, null);
    /** @type {MinMaxPyramid|null} */
    this.pyr = null;
    this.pointsPerS = 0;
    this.status = "Loading waveform…";
  }

  /** @param {import("../data/api.js").Waveform} wf */
  setPeaks(wf) {
    if (!wf.points || !wf.duration_s) {
      this.pyr = null;
      this.status = "No audio";
      return;
    }
    this.pyr = new MinMaxPyramid(Float32Array.from(wf.min), Float32Array.from(wf.max));
    this.pointsPerS = wf.points / wf.duration_s;
    this.status = "";
  }

  /** @param {string} text */
  setStatus(text) {
    this.pyr = null;
    this.status = text;
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").LaneFrame} f
   */
  draw(ctx, { width, height, view }) {
    background(ctx, width, height, [0.5]);
    if (!this.pyr) {
      message(ctx, width, height, this.status);
      return;
    }
    const { min, max } = this.cols.fill(this.pyr, view, width, this.pointsPerS);
    const mid = height / 2;
    const half = height / 2 - 2;
    ctx.fillStyle = COLORS.waveform;
    for (let x = 0; x < width; x++) {
      const hi = max[x];
      if (Number.isNaN(hi)) continue;
      const y0 = mid - hi * half;
      const y1 = mid - min[x] * half;
      ctx.fillRect(x, y0, 1, Math.max(1, y1 - y0));
    }
  }
}
