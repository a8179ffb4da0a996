/**
 * A pencil stroke: per-tick values drawn with the pointer. Ticks skipped by a fast pointer are
 * filled by linear interpolation, so the stroke always covers a contiguous tick range and becomes
 * one `pencil` op (docs/API.md) when the pointer is released.
 */

import { COLORS } from "../core/colormap.js";

export class PencilStroke {
  /**
   * @param {string} lane edit lane id ("A1".."A9", "temperature")
   * @param {number} tick
   * @param {number} value
   */
  constructor(lane, tick, value) {
    this.lane = lane;
    /** @type {Map<number, number>} */
    this.values = new Map([[tick, value]]);
    this.lastTick = tick;
    this.lastValue = value;
    this.t0 = tick;
    this.t1 = tick + 1;
  }

  /** @param {number} tick @param {number} value */
  add(tick, value) {
    const a = this.lastTick;
    const b = tick;
    const n = Math.abs(b - a);
    for (let i = 1; i <= n; i++) {
      const t = a + Math.sign(b - a) * i;
      this.values.set(t, this.lastValue + ((value - this.lastValue) * i) / n);
    }
    this.values.set(tick, value);
    this.lastTick = tick;
    this.lastValue = value;
    this.t0 = Math.min(this.t0, tick);
    this.t1 = Math.max(this.t1, tick + 1);
  }

  /** @param {number} decimals @returns {{op: "pencil", lane: string, t0: number, values: number[]}} */
  toOp(decimals) {
    const f = 10 ** decimals;
    const values = [];
    for (let t = this.t0; t < this.t1; t++) values.push(Math.round((this.values.get(t) ?? this.lastValue) * f) / f);
    return { op: "pencil", lane: this.lane, t0: this.t0, values };
  }

  /**
   * Draw the stroke over a lane.
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").TimelineView} view
   * @param {(value: number) => number} yOf
   */
  draw(ctx, view, yOf) {
    ctx.save();
    ctx.strokeStyle = COLORS.draft;
    ctx.lineWidth = 2;
    ctx.beginPath();
    let first = true;
    for (let t = this.t0; t < this.t1; t++) {
      const v = this.values.get(t);
      if (v === undefined) continue;
      const x0 = view.tickToX(t);
      const x1 = view.tickToX(t + 1);
      const y = yOf(v);
      if (first) ctx.moveTo(x0, y);
      else ctx.lineTo(x0, y);
      ctx.lineTo(x1, y);
      first = false;
    }
    ctx.stroke();
    ctx.restore();
  }
}
