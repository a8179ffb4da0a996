/**
 * The timeline core: time <-> pixel mapping, zoom, scroll, the playhead, the lane registry and
 * the selection. Lanes (../lanes/*.js) only draw and, where they edit, claim pointer gestures
 * (./gestures.js); they never touch zoom or scroll.
 *
 * Events: live ones while a gesture runs (`scrub`, `selection-input`), commit ones when it ends
 * (`seek`, `selection`); `view` on every zoom/scroll change (the editor saves it, debounced).
 */

import { h } from "./dom.js";
import { Emitter } from "./events.js";
import { wireGestures } from "./gestures.js";
import { clampLaneHeight, resizeHandle } from "./lane-resize.js";
import { RULER_HEIGHT, drawRuler } from "./ruler.js";
import { drawSelection, normaliseSelection } from "./selection.js";

export const LABEL_WIDTH = 132;
export const MAX_PX_PER_S = 400; // 40 px per 100 ms tick

/**
 * @typedef {{width: number, height: number, view: TimelineView}} LaneFrame
 * @typedef {{x: number, y: number, timeS: number, tick: number, event: PointerEvent, view: TimelineView}} LanePointer
 * @typedef {{lane: string, y0: number, y1: number}} EditRow
 * @typedef {{t0: number, t1: number, lanes: string[], ranges?: Array<[number, number]>}} Selection  ticks [t0, t1)
 *   on edit lanes; `ranges`: disjoint ranges inside it (a selection of shots)
 *
 * @typedef {Object} Lane
 * @property {string} id
 * @property {string} label
 * @property {number} height CSS pixels
 * @property {(ctx: CanvasRenderingContext2D, frame: LaneFrame) => void} draw
 * @property {string} [title] longer description (tooltip / accessible name)
 * @property {(height: number) => EditRow[]} [editRows] edit lanes this lane shows, with their y ranges
 * @property {(p: LanePointer) => boolean} [pointerDown] true when the lane takes this gesture
 * @property {(p: LanePointer) => void} [pointerMove]
 * @property {(p: LanePointer) => void} [pointerUp]
 * @property {(p: LanePointer) => void} [pointerCancel]
 * @property {(p: LanePointer) => void} [dblclick]
 * @property {(p: {x: number, y: number, view: TimelineView}) => string|null} [cursorAt]
 * @property {(el: HTMLElement) => void} [decorateLabel] add controls to the lane's label cell
 *
 * @typedef {{lane: Lane, row: HTMLElement, canvas: HTMLCanvasElement, ctx: CanvasRenderingContext2D}} LaneEntry
 *
 * @typedef {{
 *   view: {pxPerS: number, startS: number},
 *   scrub: {timeS: number},
 *   seek: {timeS: number},
 *   "selection-input": {selection: Selection|null},
 *   selection: {selection: Selection|null},
 *   "lanes-visible": {hidden: string[]},
 *   "lane-height": {id: string, height: number},
 * }} TimelineEvents
 */

/** @extends {Emitter<TimelineEvents>} */
export class TimelineView extends Emitter {
  /**
   * @param {HTMLElement} host element the timeline fills
   * @param {{durationS: number, tickS: number, frameLoop: import("./frameloop.js").FrameLoop,
   *   defaultLanes: string[]}} opts `defaultLanes`: the edit lanes of a time-only selection
   */
  constructor(host, { durationS, tickS, frameLoop, defaultLanes }) {
    super();
    this.host = host;
    this.loop = frameLoop;
    this.durationS = Math.max(tickS, durationS);
    this.tickS = tickS;
    this.nTicks = Math.max(1, Math.ceil(this.durationS / tickS - 1e-9));
    this.width = 600; // CSS px of the drawing column, set by the resize observer
    this.pxPerS = 50;
    this.startS = 0;
    this.playheadS = 0;
    this.follow = true;
    /** @type {Selection|null} */
    this.selection = null;
    /** @type {string[]} edit lanes of a time-only selection */
    this.defaultLanes = [...defaultLanes];
    /** @type {"select"|"pencil"|"points"} */
    this.tool = "select";
    /** @type {null|((ctx: CanvasRenderingContext2D, lane: Lane, frame: LaneFrame) => void)} drawn over every lane (shot lines) */
    this.overlay = null;
    /** @type {null|((tick: number) => number)} where a selection edge at `tick` snaps to (Alt: not at all) */
    this.snapTick = null;
    /** @type {LaneEntry[]} */
    this.lanes = [];
    /** @type {Set<string>} */
    this._dirty = new Set();
    this._fitted = false;
    this._build();
  }

  // ------------------------------------------------------------------ mapping
  /** @param {number} timeS */
  timeToX(timeS) {
    return (timeS - this.startS) * this.pxPerS;
  }

  /** @param {number} x */
  xToTime(x) {
    return this.startS + x / this.pxPerS;
  }

  /** @param {number} tick */
  tickToX(tick) {
    return this.timeToX(tick * this.tickS);
  }

  /** @param {number} x @returns {number} the tick under x, clamped */
  xToTick(x) {
    return this.clampTick(Math.floor(this.xToTime(x) / this.tickS));
  }

  /** @param {number} tick */
  clampTick(tick) {
    return Math.min(this.nTicks - 1, Math.max(0, tick));
  }

  get visibleS() {
    return this.width / this.pxPerS;
  }

  get endS() {
    return this.startS + this.visibleS;
  }

  get minPxPerS() {
    return Math.min(MAX_PX_PER_S, this.width / this.durationS);
  }

  // ---------------------------------------------------------- zoom & scroll
  /**
   * @param {number} pxPerS
   * @param {number} [anchorX] x (in the drawing column) that keeps its time; default the playhead or centre
   */
  setZoom(pxPerS, anchorX) {
    const z = Math.min(MAX_PX_PER_S, Math.max(this.minPxPerS, pxPerS));
    if (anchorX === undefined) {
      const ph = this.timeToX(this.playheadS);
      anchorX = ph >= 0 && ph <= this.width ? ph : this.width / 2;
    }
    const anchorT = this.xToTime(anchorX);
    this.pxPerS = z;
    this._setStart(anchorT - anchorX / z);
  }

  /** @param {number} factor @param {number} [anchorX] */
  zoomBy(factor, anchorX) {
    this.setZoom(this.pxPerS * factor, anchorX);
  }

  /** Zoom out so the whole timeline fits. */
  fit() {
    this.pxPerS = this.minPxPerS;
    this._setStart(0);
  }

  /** @param {number} startS */
  scrollTo(startS) {
    this._setStart(startS);
  }

  /** @param {number} dx pixels (positive: later) */
  panBy(dx) {
    this._setStart(this.startS + dx / this.pxPerS);
  }

  /**
   * @param {number} startS
   * @param {boolean} [silent] no `view` event (layout changes and restoring are not the user's doing)
   */
  _setStart(startS, silent = false) {
    const max = Math.max(0, this.durationS - this.visibleS);
    const s = Math.min(max, Math.max(0, startS));
    this.startS = s;
    this._updateScrollbar();
    this._placePlayhead();
    this.invalidate();
    if (!silent) this.emit("view", { pxPerS: this.pxPerS, startS: this.startS });
  }

  /** Restore saved view settings (clamped to this timeline and width). @param {{pxPerS?: number, startS?: number}} v */
  restoreView(v) {
    this._fitted = true;
    if (typeof v.pxPerS === "number" && v.pxPerS > 0) this.pxPerS = Math.min(MAX_PX_PER_S, Math.max(this.minPxPerS, v.pxPerS));
    this._setStart(typeof v.startS === "number" ? v.startS : 0, true);
  }

  // --------------------------------------------------------------- playhead
  /**
   * Move the playhead; while following, page the view when the playhead leaves it.
   * @param {number} timeS
   * @param {{page?: boolean}} [opts]
   */
  setPlayhead(timeS, opts = {}) {
    this.playheadS = Math.min(this.durationS, Math.max(0, timeS));
    if (opts.page && this.follow) {
      const x = this.timeToX(this.playheadS);
      if (x > this.width - 2 || x < 0) this._setStart(this.playheadS - this.visibleS * 0.05);
    }
    this._placePlayhead();
  }

  /** Scroll (if needed) so `timeS` is in view. @param {number} timeS */
  reveal(timeS) {
    const x = this.timeToX(timeS);
    if (x < 0 || x > this.width) this._setStart(timeS - this.visibleS / 2);
  }

  /**
   * Where the chair is (a push plays it apart from the player), as a second playhead; null hides it.
   * @param {number|null} timeS
   */
  setChairHead(timeS) {
    this.chairS = timeS;
    this._placePlayhead();
  }

  _placePlayhead() {
    for (const [el, t] of [[this.playheadEl, this.playheadS], [this.chairHeadEl, this.chairS]]) {
      const x = t === null ? NaN : this.timeToX(t);
      const visible = x >= -1 && x <= this.width + 1;
      el.style.display = visible ? "" : "none";
      if (visible) el.style.transform = `translateX(${LABEL_WIDTH + x}px)`;
    }
  }

  // ------------------------------------------------------------------ lanes
  /**
   * Register a lane; its row is appended below the others.
   * @param {Lane} lane
   */
  addLane(lane) {
    const row = h("div", { class: "tl-row" });
    row.dataset.lane = lane.id;
    row.setAttribute("data-testid", `lane-${lane.id}`);
    row.style.height = `${lane.height}px`;
    const label = h("div", { class: "tl-label" });
    const name = h("span", { class: "tl-label-name" });
    name.textContent = lane.label;
    if (lane.title) label.title = lane.title;
    label.append(name);
    if (lane.decorateLabel) lane.decorateLabel(label);
    const canvas = h("canvas", { class: "tl-canvas" });
    canvas.setAttribute("role", "img");
    canvas.setAttribute("aria-label", lane.title || lane.label);
    canvas.dataset.lane = lane.id;
    row.append(label, canvas, resizeHandle(this, lane, lane.height));
    this.lanesEl.append(row);
    const ctx = /** @type {CanvasRenderingContext2D} */ (canvas.getContext("2d"));
    const entry = { lane, row, canvas, ctx };
    this.lanes.push(entry);
    this._sizeCanvas(entry);
    this.invalidate(lane.id);
    return entry;
  }

  /** @param {string} id */
  laneEntry(id) {
    return this.lanes.find((l) => l.lane.id === id) || null;
  }

  /**
   * Give a lane another height (CSS px, clamped to LANE_HEIGHT_RANGE) and redraw it.
   * @param {string} id
   * @param {number} px
   */
  setLaneHeight(id, px) {
    const entry = this.laneEntry(id);
    if (!entry) return;
    entry.lane.height = clampLaneHeight(px);
    entry.row.style.height = `${entry.lane.height}px`;
    this._sizeCanvas(entry);
    this._resizePlayhead();
    this.invalidate(id);
  }

  /**
   * Show or hide a lane (a view setting).
   * @param {string} id
   * @param {boolean} visible
   */
  setLaneVisible(id, visible) {
    const entry = this.laneEntry(id);
    if (!entry) return;
    entry.row.hidden = !visible;
    this._resizePlayhead();
    this.invalidate(id);
    this.emit("lanes-visible", { hidden: this.lanes.filter((l) => l.row.hidden).map((l) => l.lane.id) });
  }

  /** Redraw one lane (or all, without an id) in the next frame. @param {string} [id] */
  invalidate(id) {
    if (id) this._dirty.add(id);
    else for (const l of this.lanes) this._dirty.add(l.lane.id);
    this._dirty.add("#ruler");
    this.loop.request("timeline", () => this.render());
  }

  /** Draw the dirty lanes now (normally called by the frame loop). */
  render() {
    if (this._dirty.has("#ruler")) drawRuler(this.rulerCtx, this.rulerCanvas.width / Math.max(1, this.width), this);
    for (const entry of this.lanes) {
      if (!this._dirty.has(entry.lane.id) || entry.row.hidden) continue;
      this._drawLane(entry);
    }
    this._dirty.clear();
    this.renderCount = (this.renderCount || 0) + 1;
  }

  /** @param {LaneEntry} entry */
  _drawLane(entry) {
    const { lane, canvas, ctx } = entry;
    const dpr = canvas.width / Math.max(1, this.width);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, this.width, lane.height);
    const frame = { width: this.width, height: lane.height, view: this };
    lane.draw(ctx, frame);
    if (this.overlay) this.overlay(ctx, lane, frame);
    drawSelection(ctx, lane, this.selection, this);
  }

  // -------------------------------------------------------------- selection
  /**
   * Set (or clear) the selection; a commit, so listeners save nothing but may update tools.
   * @param {Selection|null} sel
   */
  setSelection(sel) {
    this.selection = normaliseSelection(sel, this.nTicks);
    this.invalidate();
    this.emit("selection", { selection: this.selection });
  }

  // ------------------------------------------------------------------ DOM
  _build() {
    const root = h("div", { class: "tl" });
    root.tabIndex = 0;
    root.setAttribute("role", "group");
    root.setAttribute("aria-label", "Timeline: drag to select, wheel to pan, Ctrl+wheel to zoom");
    root.setAttribute("data-testid", "timeline");
    root.style.setProperty("--tl-label-width", `${LABEL_WIDTH}px`);
    const rulerRow = h("div", { class: "tl-row tl-ruler-row" });
    rulerRow.style.height = `${RULER_HEIGHT}px`;
    const rulerLabel = h("div", { class: "tl-label tl-ruler-label" });
    rulerLabel.textContent = "time";
    this.rulerCanvas = h("canvas", { class: "tl-canvas tl-ruler" });
    this.rulerCanvas.setAttribute("data-testid", "ruler");
    this.rulerCanvas.setAttribute("aria-label", "Time ruler: click or drag to move the playhead");
    this.rulerCtx = /** @type {CanvasRenderingContext2D} */ (this.rulerCanvas.getContext("2d"));
    rulerRow.append(rulerLabel, this.rulerCanvas);
    this.lanesEl = h("div", { class: "tl-lanes" });
    this.playheadEl = h("div", { class: "tl-playhead" });
    this.playheadEl.setAttribute("data-testid", "playhead");
    this.playheadEl.setAttribute("aria-hidden", "true");
    this.chairHeadEl = h("div", { class: "tl-playhead tl-chairhead", "data-testid": "chair-head", "aria-hidden": "true" });
    /** @type {number|null} the chair's position while a push plays it (s) */
    this.chairS = null;
    this.chairHeadEl.style.display = "none";
    const scroll = h("div", { class: "tl-scroll" });
    scroll.setAttribute("data-testid", "timeline-scrollbar");
    this.thumbEl = h("div", { class: "tl-scroll-thumb" });
    scroll.append(this.thumbEl);
    this.scrollEl = scroll;
    const body = h("div", { class: "tl-body" });
    body.append(rulerRow, this.lanesEl, this.playheadEl, this.chairHeadEl);
    root.append(body, scroll);
    this.root = root;
    this.bodyEl = body;
    // A lane scrolled into view (focus, the keyboard) stops below the sticky ruler, not under it.
    this.host.style.scrollPaddingTop = `${RULER_HEIGHT + 1}px`;
    this.host.append(root);

    this._ro = new ResizeObserver(() => this._resize());
    this._ro.observe(body);
    wireGestures(this);
  }

  _resize() {
    const w = Math.max(50, Math.floor(this.bodyEl.clientWidth - LABEL_WIDTH));
    const changed = w !== this.width;
    this.width = w;
    const dpr = window.devicePixelRatio || 1;
    this.rulerCanvas.width = Math.round(w * dpr);
    this.rulerCanvas.height = Math.round(RULER_HEIGHT * dpr);
    this.rulerCanvas.style.width = `${w}px`;
    this.rulerCanvas.style.height = `${RULER_HEIGHT}px`;
    for (const entry of this.lanes) this._sizeCanvas(entry);
    if (!this._fitted) {
      this._fitted = true;
      this.pxPerS = this.minPxPerS;
      this._setStart(0, true);
    } else if (changed) {
      this.pxPerS = Math.max(this.minPxPerS, this.pxPerS);
      this._setStart(this.startS, true);
    }
    this._resizePlayhead();
    this.invalidate();
  }

  _resizePlayhead() {
    this.playheadEl.style.height = this.chairHeadEl.style.height = `${this.bodyEl.scrollHeight}px`;
  }

  /** @param {{lane: Lane, canvas: HTMLCanvasElement}} entry */
  _sizeCanvas(entry) {
    const dpr = window.devicePixelRatio || 1;
    entry.canvas.width = Math.round(this.width * dpr);
    entry.canvas.height = Math.round(entry.lane.height * dpr);
    entry.canvas.style.width = `${this.width}px`;
    entry.canvas.style.height = `${entry.lane.height}px`;
  }

  _updateScrollbar() {
    const frac = Math.min(1, this.visibleS / this.durationS);
    const left = this.durationS > 0 ? this.startS / this.durationS : 0;
    this.thumbEl.style.left = `${left * 100}%`;
    this.thumbEl.style.width = `${Math.max(frac * 100, 1.5)}%`;
  }

  /** @param {number} t seconds, clamped to the timeline */
  clampTime(t) {
    return Math.min(this.durationS, Math.max(0, t));
  }

  destroy() {
    this._ro.disconnect();
    this.clearListeners();
    this.root.remove();
  }
}
