/**
 * The temperature the chair plays (GET /timeline/chair-temperature, docs/API.md): the composed
 * target after the device's clamp and slew limit, computed by the server (chair/comfort.py
 * DeviceProfile), with the device's limits. The temperature lane draws it beside the target.
 */

import { MinMaxPyramid } from "./pyramid.js";

export class PlayedTemperature {
  /**
   * @param {{revision: number, tick_s: number, min_c: number, max_c: number, neutral_c: number,
   *   rate_c_per_s: number, values: number[]}} answer
   */
  constructor(answer) {
    this.revision = answer.revision;
    this.minC = answer.min_c;
    this.maxC = answer.max_c;
    this.neutralC = answer.neutral_c;
    this.rateCPerS = answer.rate_c_per_s;
    /** @type {Float32Array} C per tick */
    this.values = Float32Array.from(answer.values);
    this.pyr = new MinMaxPyramid(this.values);
    let lo = Infinity;
    let hi = -Infinity;
    for (const v of this.values) {
      if (v < lo) lo = v;
      if (v > hi) hi = v;
    }
    this.lo = lo;
    this.hi = hi;
  }

  /** @param {number} tick @returns {number} C, NaN outside the timeline */
  at(tick) {
    const k = Math.floor(tick);
    return k >= 0 && k < this.values.length ? this.values[k] : NaN;
  }
}
