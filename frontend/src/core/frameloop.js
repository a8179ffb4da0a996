/**
 * One requestAnimationFrame driver for the whole editor: one-shot jobs keyed so a frame runs each
 * at most once (redraw requests coalesce), and persistent per-frame callbacks (the playback clock).
 * It also records how long each frame's work took and the interval between frames, which is what
 * the benchmark reads (window.autohaptics.perf()).
 */

const RING = 1200;

export class FrameLoop {
  constructor() {
    /** @type {Map<string, () => void>} */
    this._once = new Map();
    /** @type {Set<(now: number) => void>} */
    this._every = new Set();
    this._scheduled = false;
    this._lastFrame = 0;
    this._work = new Float64Array(RING);
    this._delta = new Float64Array(RING);
    this._count = 0;
    this._deltaCount = 0;
    this._run = this._run.bind(this);
  }

  /**
   * Run `fn` in the next frame (a second request with the same key in the same frame replaces it).
   * @param {string} key
   * @param {() => void} fn
   */
  request(key, fn) {
    this._once.set(key, fn);
    this._schedule();
  }

  /**
   * Call `fn(now)` every frame until the returned function is called.
   * @param {(now: number) => void} fn
   * @returns {() => void}
   */
  add(fn) {
    this._every.add(fn);
    this._schedule();
    return () => {
      this._every.delete(fn);
    };
  }

  _schedule() {
    if (this._scheduled) return;
    this._scheduled = true;
    requestAnimationFrame(this._run);
  }

  /** @param {number} now */
  _run(now) {
    this._scheduled = false;
    const t0 = performance.now();
    if (this._lastFrame && this._every.size) {
      this._delta[this._deltaCount % RING] = now - this._lastFrame;
      this._deltaCount++;
    }
    this._lastFrame = this._every.size ? now : 0;
    for (const fn of [...this._every]) fn(now);
    const once = [...this._once.values()];
    this._once.clear();
    for (const fn of once) fn();
    this._work[this._count % RING] = performance.now() - t0;
    this._count++;
    if (this._every.size || this._once.size) this._schedule();
  }

  /** Forget the recorded frame times (start of a measurement). */
  resetStats() {
    this._count = 0;
    this._deltaCount = 0;
  }

  /**
   * Percentiles of the recorded frames (ms): `work` = time spent in this frame's callbacks,
   * `interval` = time between consecutive frames while a per-frame callback (playback) runs.
   */
  stats() {
    return {
      frames: Math.min(this._count, RING),
      work: summary(this._work, Math.min(this._count, RING)),
      interval: summary(this._delta, Math.min(this._deltaCount, RING)),
    };
  }
}

/**
 * @param {Float64Array} ring
 * @param {number} n
 */
function summary(ring, n) {
  if (!n) return { n: 0, p50: NaN, p95: NaN, max: NaN, mean: NaN };
  const a = Array.from(ring.subarray(0, n)).sort((x, y) => x - y);
  const pick = (/** @type {number} */ q) => a[Math.min(n - 1, Math.ceil(q * n) - 1)];
  return { n, p50: pick(0.5), p95: pick(0.95), max: a[n - 1], mean: a.reduce((s, v) => s + v, 0) / n };
}
