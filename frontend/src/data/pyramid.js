/**
 * Min/max pyramids: level L holds the min and max of buckets of 2^L consecutive samples, so the
 * envelope of any pixel column is read from at most three buckets whatever the zoom. This is what
 * keeps drawing a 72,000-tick timeline proportional to the canvas width, not to the film length.
 */

/** @typedef {Uint8Array|Float32Array} Samples */

export class MinMaxPyramid {
  /**
   * @param {Samples} lo per-sample lower values (the values themselves for a plain curve)
   * @param {Samples} [hi] per-sample upper values (defaults to `lo`)
   */
  constructor(lo, hi = lo) {
    if (lo.length !== hi.length) throw new Error(`pyramid: lo and hi lengths differ (${lo.length} vs ${hi.length})`);
    this.length = lo.length;
    /** @type {{min: Samples, max: Samples}[]} */
    this.levels = [{ min: lo, max: hi }];
    let prevMin = lo;
    let prevMax = hi;
    while (prevMin.length > 1) {
      const n = Math.ceil(prevMin.length / 2);
      const Ctor = /** @type {any} */ (prevMin.constructor);
      /** @type {Samples} */
      const mn = new Ctor(n);
      /** @type {Samples} */
      const mx = new Ctor(n);
      const last = prevMin.length - 1;
      for (let i = 0; i < n; i++) {
        const a = 2 * i;
        const b = a + 1 > last ? a : a + 1;
        mn[i] = prevMin[a] < prevMin[b] ? prevMin[a] : prevMin[b];
        mx[i] = prevMax[a] > prevMax[b] ? prevMax[a] : prevMax[b];
      }
      this.levels.push({ min: mn, max: mx });
      prevMin = mn;
      prevMax = mx;
    }
  }

  /**
   * Fill per-column envelopes: column i covers samples [start + i * perCol, start + (i + 1) * perCol).
   * A column outside the data gets NaN. When a column is narrower than one sample it takes the
   * sample under it, so zoomed-in curves come out as steps.
   * @param {number} start first sample (may be fractional or negative)
   * @param {number} perCol samples per column (> 0)
   * @param {number} nCols
   * @param {Float32Array} outMin
   * @param {Float32Array} outMax
   */
  fillColumns(start, perCol, nCols, outMin, outMax) {
    const n = this.length;
    const level = perCol <= 2 ? 0 : Math.min(this.levels.length - 1, Math.floor(Math.log2(perCol)) - 1);
    const { min, max } = this.levels[level];
    for (let i = 0; i < nCols; i++) {
      let a = Math.floor(start + i * perCol);
      let b = Math.floor(start + (i + 1) * perCol);
      if (b <= a) b = a + 1;
      if (a >= n || b <= 0) {
        outMin[i] = NaN;
        outMax[i] = NaN;
        continue;
      }
      if (a < 0) a = 0;
      if (b > n) b = n;
      const ba = a >> level;
      const bb = (b - 1) >> level;
      let lo = min[ba];
      let hi = max[ba];
      for (let k = ba + 1; k <= bb; k++) {
        if (min[k] < lo) lo = min[k];
        if (max[k] > hi) hi = max[k];
      }
      outMin[i] = lo;
      outMax[i] = hi;
    }
  }
}

/**
 * One channel of an interleaved array: `data[i * stride + channel]` for i in 0..n-1.
 * @template {Samples} T
 * @param {T} data
 * @param {number} n
 * @param {number} stride
 * @param {number} channel
 * @returns {T}
 */
export function channel(data, n, stride, channel) {
  const Ctor = /** @type {any} */ (data.constructor);
  const out = new Ctor(n);
  for (let i = 0, j = channel; i < n; i++, j += stride) out[i] = data[j];
  return out;
}
