/**
 * Pictures for the canvas (posters, filmstrip tiles) kept decoded in memory, bounded by their
 * pixel count (least recently drawn dropped first). Drawing never waits: `get` answers a decoded
 * image or null and asks for the missing one; a few loads run at a time, the ones asked for in the
 * latest draw first, and a request no draw asked for since is dropped (a fast scroll does not queue
 * the whole film). `onLoad` says when a picture arrived, so the caller redraws.
 */

const RETRY_MS = 5000;

/** @typedef {{img: ImageBitmap|null, pixels: number, used: number, state: "queued"|"loading"|"ready"|"failed", at: number}} Entry */

export class ImageCache {
  /**
   * @param {{maxPixels?: number, concurrency?: number, onLoad?: (url: string) => void}} [opts]
   *   maxPixels: decoded pixels kept (4 bytes each; 12 M is 48 MB)
   */
  constructor({ maxPixels = 12e6, concurrency = 4, onLoad = () => {} } = {}) {
    this.maxPixels = maxPixels;
    this.concurrency = concurrency;
    this.onLoad = onLoad;
    /** @type {Map<string, Entry>} */
    this.entries = new Map();
    this.pixels = 0;
    this.inFlight = 0;
    /** draw pass counter: a queued request older than the previous pass is dropped */
    this.pass = 0;
    this.loaded = 0;
    this.disposed = false;
    this._pumpQueued = false;
  }

  /** Start a draw pass (requests from older passes are no longer wanted). */
  beginPass() {
    this.pass++;
  }

  /** A decoded picture, or null (then it is asked for). @param {string} url */
  get(url) {
    const e = this.entries.get(url);
    if (e && e.state === "ready") {
      e.used = this.pass;
      return e.img;
    }
    if (!e || (e.state === "failed" && performance.now() - e.at > RETRY_MS)) {
      this.entries.set(url, { img: null, pixels: 0, used: this.pass, state: "queued", at: 0 });
    } else if (e.state === "queued") {
      e.used = this.pass;
    }
    if (!this._pumpQueued) {
      this._pumpQueued = true;
      queueMicrotask(() => {
        this._pumpQueued = false;
        this._pump();
      });
    }
    return null;
  }

  /** Whether a picture is decoded and kept. @param {string} url */
  has(url) {
    const e = this.entries.get(url);
    return !!e && e.state === "ready";
  }

  _pump() {
    while (this.inFlight < this.concurrency) {
      let next = null;
      for (const [url, e] of this.entries) {
        if (e.state !== "queued") continue;
        if (e.used < this.pass - 1) {
          this.entries.delete(url); // no draw wants it any more
          continue;
        }
        if (!next || e.used > next[1].used) next = [url, e];
      }
      if (!next) return;
      this._load(next[0], next[1]);
    }
  }

  /** @param {string} url @param {Entry} e */
  async _load(url, e) {
    e.state = "loading";
    this.inFlight++;
    try {
      // An ImageBitmap is decoded once, off the main thread, and stays decoded: drawing it costs a
      // copy (an <img> may be decoded again on the frame that first draws it).
      const res = await fetch(url);
      if (!res.ok) throw new Error(`${res.status}`);
      const img = await createImageBitmap(await res.blob());
      if (this.disposed) {
        img.close();
        return;
      }
      e.img = img;
      e.pixels = img.width * img.height;
      e.state = "ready";
      this.pixels += e.pixels;
      this.loaded++;
      this._evict();
      this.onLoad(url);
    } catch {
      e.state = "failed";
      e.at = performance.now();
    } finally {
      this.inFlight--;
      if (!this.disposed) this._pump();
    }
  }

  /** Drop the least recently drawn pictures while over the bound (never one of this pass). */
  _evict() {
    if (this.pixels <= this.maxPixels) return;
    const ready = [...this.entries].filter(([, e]) => e.state === "ready" && e.used < this.pass).sort((a, b) => a[1].used - b[1].used);
    for (const [url, e] of ready) {
      if (this.pixels <= this.maxPixels) break;
      this.entries.delete(url);
      this.pixels -= e.pixels;
      if (e.img) e.img.close();
    }
  }

  /** What is held, for the debug handle. */
  stats() {
    let ready = 0;
    for (const e of this.entries.values()) if (e.state === "ready") ready++;
    return { ready, pixels: this.pixels, loaded: this.loaded, inFlight: this.inFlight };
  }

  dispose() {
    this.disposed = true;
    for (const e of this.entries.values()) if (e.img) e.img.close();
    this.entries.clear();
    this.pixels = 0;
  }
}
