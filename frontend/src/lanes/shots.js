/**
 * The Shots lane under the ruler: the filmstrip (frames of the film along time, from the
 * server's tiles at the step nearest the on-screen frame width; each shot's poster until the
 * filmstrip is served), each shot's colour while its picture loads, the selected shots outlined
 * and the shots a similarity preview would pick marked. Click a shot to select it, Shift-click to
 * add one (or take it out), drag across shots to select a run, double-click to play one.
 * Only what is on screen is drawn; pictures come from an ImageCache and are never waited for.
 */

import { COLORS } from "../core/colormap.js";
import { rangesOf } from "../core/selection.js";
import { BaseLane, background, message } from "./common.js";

const PAD = 2;
const DRAG_PX = 4;
/** a shot narrower than this (px) shows its colour only, no poster */
const MIN_POSTER_PX = 12;

/**
 * @typedef {import("../data/shot-list.js").Shot} Shot
 * @typedef {import("../data/shot-list.js").ShotList} ShotList
 * @typedef {{frame_w: number, frame_h: number, per_tile: number, steps: number[]}} Filmstrip
 * @typedef {{
 *   shots: () => ShotList|null,
 *   status: () => string,
 *   filmstrip: () => Filmstrip|null,
 *   cache: import("../data/image-cache.js").ImageCache,
 *   posterUrl: (shot: Shot) => string,
 *   tileUrl: (step: number, tile: number) => string,
 *   preview: () => Set<number>,
 *   onClick: (shot: Shot, add: boolean) => void,
 *   onRun: (from: Shot, to: Shot, add: boolean) => void,
 *   onPlay: (shot: Shot) => void,
 * }} ShotsHooks
 */

/** The step of `steps` whose frame spacing is nearest (in ratio) to the frame width. @param {number[]} steps @param {number} ideal */
export function nearestStep(steps, ideal) {
  let best = steps[0];
  for (const s of steps) if (Math.abs(Math.log(s / ideal)) < Math.abs(Math.log(best / ideal))) best = s;
  return best;
}

/** @extends {BaseLane<ShotsHooks>} */
export class ShotsLane extends BaseLane {
  /** @param {ShotsHooks} hooks */
  constructor(hooks) {
    super({ id: "shots", label: "Shots", title: "Shots: click to select a shot, Shift-click to add one, drag across shots, double-click to play one; right-click for split and merge", height: 45 + 2 * PAD }, hooks);
    /** @type {{i0: number, x: number, moved: boolean}|null} */
    this.press = null;
    /** the filmstrip step drawn last (for the debug handle) */
    this.step = 0;
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").LaneFrame} f
   */
  draw(ctx, { width, height, view }) {
    background(ctx, width, height);
    const list = this.hooks.shots();
    if (!list || !list.length) {
      message(ctx, width, height, this.hooks.status());
      return;
    }
    const cache = this.hooks.cache;
    cache.beginPass();
    const tickS = view.tickS;
    const tA = Math.max(0, Math.floor(view.startS / tickS));
    const tB = Math.min(list.nTicks, Math.ceil(view.endS / tickS) + 1);
    const i0 = list.indexAt(tA);
    const i1 = list.indexAt(tB - 1);
    const y = PAD;
    const dh = height - 2 * PAD;
    // Each shot's colour first: what shows while its pictures load.
    let lastX = -Infinity;
    for (let i = i0; i <= i1; i++) {
      const s = list.shots[i];
      const x0 = Math.max(0, view.tickToX(s.t0));
      const x1 = Math.min(width, view.tickToX(s.t1));
      if (x1 - lastX < 1 && x1 - x0 < 1) continue;
      ctx.fillStyle = s.colour || "#1c2230";
      ctx.fillRect(Math.floor(x0), y, Math.max(1, Math.ceil(x1) - Math.floor(x0)), dh);
      lastX = x1;
    }
    const strip = this.hooks.filmstrip();
    if (strip) this._drawStrip(ctx, strip, view, tA, tB, y, dh, list.nTicks);
    else this._drawPosters(ctx, list, view, i0, i1, y, dh, width);
    this._drawMarks(ctx, list, view, i0, i1, height);
  }

  /**
   * @param {CanvasRenderingContext2D} ctx @param {Filmstrip} strip
   * @param {import("../core/timeline.js").TimelineView} view
   * @param {number} tA @param {number} tB visible ticks @param {number} y @param {number} dh @param {number} nTicks
   */
  _drawStrip(ctx, strip, view, tA, tB, y, dh, nTicks) {
    const pxPerTick = view.pxPerS * view.tickS;
    const fw = (strip.frame_w * dh) / strip.frame_h;
    const step = nearestStep(strip.steps, fw / pxPerTick);
    this.step = step;
    const slot = step * pxPerTick;
    const per = strip.per_tile;
    for (let k = Math.floor(tA / step); k * step < tB && k * step < nTicks; k++) {
      const tile = Math.floor(k / per);
      const img = this.hooks.cache.get(this.hooks.tileUrl(step, tile));
      if (!img) continue;
      const f = k - tile * per;
      coverDraw(ctx, img, f * strip.frame_w, 0, strip.frame_w, img.height, view.tickToX(k * step), y, slot, dh);
    }
  }

  /**
   * @param {CanvasRenderingContext2D} ctx @param {ShotList} list
   * @param {import("../core/timeline.js").TimelineView} view
   * @param {number} i0 @param {number} i1 @param {number} y @param {number} dh @param {number} width
   */
  _drawPosters(ctx, list, view, i0, i1, y, dh, width) {
    this.step = 0;
    for (let i = i0; i <= i1; i++) {
      const s = list.shots[i];
      const x0 = view.tickToX(s.t0);
      const x1 = view.tickToX(s.t1);
      if (x1 - x0 < MIN_POSTER_PX) continue;
      const img = this.hooks.cache.get(this.hooks.posterUrl(s));
      if (!img) continue;
      // The poster repeated along the shot at its own aspect, like frames of a filmstrip.
      const fw = (img.width * dh) / Math.max(1, img.height);
      const end = Math.min(x1, width + 1);
      let x = x0 < -fw ? x0 + Math.floor(-x0 / fw) * fw : x0;
      for (; x < end; x += fw) coverDraw(ctx, img, 0, 0, img.width, img.height, x, y, Math.min(fw, x1 - x), dh);
    }
  }

  /** Selected shots outlined, previewed ones marked. @param {CanvasRenderingContext2D} ctx @param {ShotList} list @param {import("../core/timeline.js").TimelineView} view @param {number} i0 @param {number} i1 @param {number} height */
  _drawMarks(ctx, list, view, i0, i1, height) {
    const preview = this.hooks.preview();
    if (preview.size) {
      ctx.fillStyle = "rgba(250, 204, 21, 0.28)";
      ctx.strokeStyle = COLORS.marker;
      ctx.lineWidth = 2;
      for (let i = i0; i <= i1; i++) {
        const s = list.shots[i];
        if (!preview.has(s.id)) continue;
        const x0 = view.tickToX(s.t0);
        const w = Math.max(1, view.tickToX(s.t1) - x0);
        ctx.fillRect(x0, 0, w, height);
        ctx.strokeRect(x0 + 1, 1, Math.max(0, w - 2), height - 2);
      }
    }
    const sel = view.selection;
    if (!sel) return;
    ctx.strokeStyle = "#93c5fd";
    ctx.lineWidth = 2;
    for (const [t0, t1] of rangesOf(sel)) {
      const x0 = view.tickToX(t0);
      const x1 = view.tickToX(t1);
      if (x1 < 0 || x0 > view.width) continue;
      ctx.strokeRect(x0 + 1, 1, Math.max(0, x1 - x0 - 2), height - 2);
    }
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerDown(p) {
    const list = this.hooks.shots();
    if (!list || !list.length) return false;
    this.press = { i0: list.indexAt(p.tick), x: p.x, moved: false };
    return true;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerMove(p) {
    const list = this.hooks.shots();
    if (!this.press || !list) return;
    if (!this.press.moved && Math.abs(p.x - this.press.x) < DRAG_PX) return;
    this.press.moved = true;
    const a = list.shots[this.press.i0];
    const b = list.shots[list.indexAt(p.tick)];
    this.hooks.onRun(a, b, p.event.shiftKey);
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerUp(p) {
    const list = this.hooks.shots();
    const press = this.press;
    this.press = null;
    if (!press || !list || press.moved) return;
    this.hooks.onClick(list.shots[press.i0], p.event.shiftKey);
  }

  pointerCancel() {
    this.press = null;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  dblclick(p) {
    const list = this.hooks.shots();
    const shot = list && list.at(p.tick);
    if (shot) this.hooks.onPlay(shot);
  }

  cursorAt() {
    return "pointer";
  }
}

/**
 * Draw a source rectangle into a destination one at its own aspect, cropped to fill it (cover).
 * @param {CanvasRenderingContext2D} ctx @param {CanvasImageSource} img
 * @param {number} sx @param {number} sy @param {number} sw @param {number} sh
 * @param {number} dx @param {number} dy @param {number} dw @param {number} dh
 */
function coverDraw(ctx, img, sx, sy, sw, sh, dx, dy, dw, dh) {
  if (dw <= 0 || dh <= 0 || sw <= 0 || sh <= 0) return;
  const k = Math.max(dw / sw, dh / sh);
  const cw = dw / k;
  const ch = dh / k;
  ctx.drawImage(img, sx + (sw - cw) / 2, sy + (sh - ch) / 2, cw, ch, dx, dy, dw, dh);
}
