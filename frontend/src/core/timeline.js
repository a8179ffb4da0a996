/**
 * The timeline core: time <-> pixel mapping, zoom, scroll, the playhead, the lane registry, the
 * selection, and the pointer/wheel gestures common to every lane. Lanes (../lanes/*.js) only draw
 * and, where they edit, claim pointer gestures; they never touch zoom or scroll.
 *
 * Events: live ones while a gesture runs (`scrub`, `selection-input`), commit ones when it ends
 * (`seek`, `selection`); `view` on every zoom/scroll change (the editor saves it, debounced).
 */

import { Emitter } from "./events.js";

export const LABEL_WIDTH = 132;
export const RULER_HEIGHT = 24;
export const MAX_PX_PER_S = 400; // 40 px per 100 ms tick
const DRAG_THRESHOLD_PX = 3;

/**
 * @typedef {{width: number, height: number, view: TimelineView}} LaneFrame
 * @typedef {{x: number, y: number, timeS: number, tick: number, event: PointerEvent, view: TimelineView}} LanePointer
 * @typedef {{lane: string, y0: number, y1: number}} EditRow
 * @typedef {{t0: number, t1: number, lanes: string[]}} Selection  ticks [t0, t1) on edit lanes
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
 * @typedef {{
 *   view: {pxPerS: number, startS: number},
 *   scrub: {timeS: number},
 *   seek: {timeS: number},
 *   "selection-input": {selection: Selection|null},
 *   selection: {selection: Selection|null},
 *   "lanes-visible": {hidden: string[]},
 * }} TimelineEvents
 */

/** @extends {Emitter<TimelineEvents>} */
export class TimelineView extends Emitter {
  /**
   * @param {HTMLElement} host element the timeline fills
   * @param {{durationS: number, tickS: number, frameLoop: import("./frameloop.js").FrameLoop}} opts
   */
  constructor(host, { durationS, tickS, frameLoop }) {
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
    /** @type {string[]} default edit lanes of a time-only selection */
    this.defaultLanes = ["A1", "A2", "A3", "A4", "A5", "A6", "A7", "A8", "A9"];
    /** @type {"select"|"pencil"|"points"} */
    this.tool = "select";
    /** @type {{lane: Lane, row: HTMLElement, canvas: HTMLCanvasElement, ctx: CanvasRenderingContext2D}[]} */
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

  _placePlayhead() {
    const x = this.timeToX(this.playheadS);
    const visible = x >= -1 && x <= this.width + 1;
    this.playheadEl.style.display = visible ? "" : "none";
    if (visible) this.playheadEl.style.transform = `translateX(${LABEL_WIDTH + x}px)`;
  }

  // ------------------------------------------------------------------ lanes
  /**
   * Register a lane; its row is appended below the others.
   * @param {Lane} lane
   */
  addLane(lane) {
    const row = el("div", "tl-row");
    row.dataset.lane = lane.id;
    row.setAttribute("data-testid", `lane-${lane.id}`);
    row.style.height = `${lane.height}px`;
    const label = el("div", "tl-label");
    const name = el("span", "tl-label-name");
    name.textContent = lane.label;
    if (lane.title) label.title = lane.title;
    label.append(name);
    if (lane.decorateLabel) lane.decorateLabel(label);
    const canvas = /** @type {HTMLCanvasElement} */ (el("canvas", "tl-canvas"));
    canvas.setAttribute("role", "img");
    canvas.setAttribute("aria-label", lane.title || lane.label);
    canvas.dataset.lane = lane.id;
    row.append(label, canvas);
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
    if (this._dirty.has("#ruler")) this._drawRuler();
    for (const entry of this.lanes) {
      if (!this._dirty.has(entry.lane.id) || entry.row.hidden) continue;
      this._drawLane(entry);
    }
    this._dirty.clear();
    this.renderCount = (this.renderCount || 0) + 1;
  }

  /** @param {{lane: Lane, canvas: HTMLCanvasElement, ctx: CanvasRenderingContext2D}} entry */
  _drawLane(entry) {
    const { lane, canvas, ctx } = entry;
    const dpr = canvas.width / Math.max(1, this.width);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, this.width, lane.height);
    lane.draw(ctx, { width: this.width, height: lane.height, view: this });
    this._drawSelection(ctx, lane);
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {Lane} lane
   */
  _drawSelection(ctx, lane) {
    const sel = this.selection;
    if (!sel) return;
    const x0 = this.tickToX(sel.t0);
    const x1 = this.tickToX(sel.t1);
    if (x1 < 0 || x0 > this.width) return;
    const rows = lane.editRows ? lane.editRows(lane.height) : [];
    const chosen = rows.filter((r) => sel.lanes.includes(r.lane));
    ctx.save();
    if (chosen.length) {
      ctx.fillStyle = "rgba(96, 165, 250, 0.22)";
      ctx.strokeStyle = "rgba(147, 197, 253, 0.9)";
      ctx.lineWidth = 1;
      for (const r of chosen) {
        ctx.fillRect(x0, r.y0, x1 - x0, r.y1 - r.y0);
        ctx.strokeRect(x0 + 0.5, r.y0 + 0.5, Math.max(0, x1 - x0 - 1), r.y1 - r.y0 - 1);
      }
    } else {
      ctx.fillStyle = "rgba(96, 165, 250, 0.07)";
      ctx.fillRect(x0, 0, x1 - x0, lane.height);
    }
    ctx.restore();
  }

  _drawRuler() {
    const canvas = this.rulerCanvas;
    const ctx = this.rulerCtx;
    const dpr = canvas.width / Math.max(1, this.width);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, this.width, RULER_HEIGHT);
    const step = niceStep(80 / this.pxPerS);
    const minor = step / 5;
    ctx.fillStyle = "#8b93a7";
    ctx.strokeStyle = "#3a4152";
    ctx.font = "11px system-ui, sans-serif";
    ctx.textBaseline = "top";
    ctx.beginPath();
    const first = Math.floor(this.startS / minor) * minor;
    for (let t = first; t <= this.endS + minor; t += minor) {
      const x = Math.round(this.timeToX(t)) + 0.5;
      const major = Math.abs(t / step - Math.round(t / step)) < 1e-6;
      ctx.moveTo(x, major ? 12 : 18);
      ctx.lineTo(x, RULER_HEIGHT);
      if (major && t >= 0) ctx.fillText(formatRulerTime(t, step), x + 3, 2);
    }
    ctx.stroke();
    const sel = this.selection;
    if (sel) {
      ctx.fillStyle = "rgba(96, 165, 250, 0.35)";
      ctx.fillRect(this.tickToX(sel.t0), RULER_HEIGHT - 5, this.tickToX(sel.t1) - this.tickToX(sel.t0), 5);
    }
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

  /** Edit rows of every visible lane, top to bottom, with y relative to the lanes container. */
  _allEditRows() {
    /** @type {{lane: string, top: number, bottom: number}[]} */
    const out = [];
    for (const { lane, row } of this.lanes) {
      if (row.hidden || !lane.editRows) continue;
      const top = row.offsetTop;
      for (const r of lane.editRows(lane.height)) out.push({ lane: r.lane, top: top + r.y0, bottom: top + r.y1 });
    }
    return out;
  }

  // ------------------------------------------------------------------ DOM
  _build() {
    const root = el("div", "tl");
    root.tabIndex = 0;
    root.setAttribute("role", "group");
    root.setAttribute("aria-label", "Timeline: drag to select, wheel to pan, Ctrl+wheel to zoom");
    root.setAttribute("data-testid", "timeline");
    root.style.setProperty("--tl-label-width", `${LABEL_WIDTH}px`);
    const rulerRow = el("div", "tl-row tl-ruler-row");
    rulerRow.style.height = `${RULER_HEIGHT}px`;
    const rulerLabel = el("div", "tl-label tl-ruler-label");
    rulerLabel.textContent = "time";
    this.rulerCanvas = /** @type {HTMLCanvasElement} */ (el("canvas", "tl-canvas tl-ruler"));
    this.rulerCanvas.setAttribute("data-testid", "ruler");
    this.rulerCanvas.setAttribute("aria-label", "Time ruler: click or drag to move the playhead");
    this.rulerCtx = /** @type {CanvasRenderingContext2D} */ (this.rulerCanvas.getContext("2d"));
    rulerRow.append(rulerLabel, this.rulerCanvas);
    this.lanesEl = el("div", "tl-lanes");
    this.playheadEl = el("div", "tl-playhead");
    this.playheadEl.setAttribute("data-testid", "playhead");
    this.playheadEl.setAttribute("aria-hidden", "true");
    const scroll = el("div", "tl-scroll");
    scroll.setAttribute("data-testid", "timeline-scrollbar");
    this.thumbEl = el("div", "tl-scroll-thumb");
    scroll.append(this.thumbEl);
    this.scrollEl = scroll;
    const body = el("div", "tl-body");
    body.append(rulerRow, this.lanesEl, this.playheadEl);
    root.append(body, scroll);
    this.root = root;
    this.bodyEl = body;
    this.host.append(root);

    this._ro = new ResizeObserver(() => this._resize());
    this._ro.observe(body);
    this._wireRuler();
    this._wireLanes();
    this._wireWheel();
    this._wireScrollbar();
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
    this.playheadEl.style.height = `${this.bodyEl.scrollHeight}px`;
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

  _wireRuler() {
    const c = this.rulerCanvas;
    c.addEventListener("pointerdown", (e) => {
      if (e.button !== 0) return;
      e.preventDefault();
      c.setPointerCapture(e.pointerId);
      const at = (/** @type {PointerEvent} */ ev) => this._clampTime(this.xToTime(ev.offsetX));
      this.setPlayhead(at(e));
      this.emit("scrub", { timeS: this.playheadS });
      const move = (/** @type {PointerEvent} */ ev) => {
        this.setPlayhead(at(ev));
        this.emit("scrub", { timeS: this.playheadS });
      };
      const up = (/** @type {PointerEvent} */ ev) => {
        c.removeEventListener("pointermove", move);
        c.removeEventListener("pointerup", up);
        c.removeEventListener("pointercancel", up);
        this.setPlayhead(at(ev));
        this.emit("seek", { timeS: this.playheadS });
      };
      c.addEventListener("pointermove", move);
      c.addEventListener("pointerup", up);
      c.addEventListener("pointercancel", up);
    });
  }

  /** @param {number} t */
  _clampTime(t) {
    return Math.min(this.durationS, Math.max(0, t));
  }

  _wireLanes() {
    const host = this.lanesEl;
    host.addEventListener("pointerdown", (e) => {
      const canvas = /** @type {HTMLElement} */ (e.target);
      if (!(canvas instanceof HTMLCanvasElement)) return;
      const entry = this.lanes.find((l) => l.canvas === canvas);
      if (!entry) return;
      this.root.focus({ preventScroll: true });
      const pointer = (/** @type {PointerEvent} */ ev) => {
        const r = canvas.getBoundingClientRect();
        const x = ev.clientX - r.left;
        const y = ev.clientY - r.top;
        const timeS = this._clampTime(this.xToTime(x));
        return { x, y, timeS, tick: this.xToTick(x), event: ev, view: this };
      };
      const p0 = pointer(e);
      canvas.setPointerCapture(e.pointerId);
      e.preventDefault();
      // Middle button or Alt+drag pans whatever the tool.
      if (e.button === 1 || (e.button === 0 && e.altKey)) {
        this._gesture(canvas, (ev) => this.panBy(-(ev.movementX || 0)), () => {});
        return;
      }
      if (e.button !== 0) return;
      const lane = entry.lane;
      if (lane.pointerDown && lane.pointerDown(p0)) {
        this._gesture(
          canvas,
          (ev) => lane.pointerMove && lane.pointerMove(pointer(ev)),
          (ev, cancelled) => {
            if (cancelled) lane.pointerCancel && lane.pointerCancel(pointer(ev));
            else lane.pointerUp && lane.pointerUp(pointer(ev));
          },
        );
        return;
      }
      this._selectGesture(canvas, entry, p0, pointer);
    });
    host.addEventListener("dblclick", (e) => {
      const canvas = e.target;
      if (!(canvas instanceof HTMLCanvasElement)) return;
      const entry = this.lanes.find((l) => l.canvas === canvas);
      if (!entry || !entry.lane.dblclick) return;
      const x = e.offsetX;
      entry.lane.dblclick({
        x, y: e.offsetY, timeS: this._clampTime(this.xToTime(x)), tick: this.xToTick(x),
        event: /** @type {PointerEvent} */ (/** @type {unknown} */ (e)), view: this,
      });
    });
    host.addEventListener("pointermove", (e) => {
      if (e.buttons) return;
      const canvas = e.target;
      if (!(canvas instanceof HTMLCanvasElement)) return;
      const entry = this.lanes.find((l) => l.canvas === canvas);
      if (!entry) return;
      const cur = entry.lane.cursorAt ? entry.lane.cursorAt({ x: e.offsetX, y: e.offsetY, view: this }) : null;
      canvas.style.cursor = cur || (this.tool === "pencil" && entry.lane.editRows ? "crosshair" : "default");
    });
  }

  /**
   * Drag on a lane: a click seeks, a drag selects a tick range on the edit rows it crosses.
   * @param {HTMLCanvasElement} canvas
   * @param {{lane: Lane, row: HTMLElement}} entry
   * @param {LanePointer} p0
   * @param {(ev: PointerEvent) => LanePointer} pointer
   */
  _selectGesture(canvas, entry, p0, pointer) {
    const rows = this._allEditRows();
    const yAbs = (/** @type {LanePointer} */ p) => entry.row.offsetTop + p.y;
    const rowIndexAt = (/** @type {number} */ y) => rows.findIndex((r) => y >= r.top && y < r.bottom);
    const startRow = rowIndexAt(yAbs(p0));
    const prev = this.selection;
    const extend = p0.event.shiftKey && prev;
    const anchorTick = extend ? (p0.tick < prev.t0 ? prev.t1 : prev.t0) : p0.tick;
    let dragged = false;
    /** @param {LanePointer} p @returns {Selection} */
    const selAt = (p) => {
      const tickHere = p.tick;
      const t0 = Math.min(anchorTick, tickHere);
      const t1 = Math.max(anchorTick, tickHere) + 1;
      /** @type {string[]} */
      let lanes;
      if (startRow >= 0) {
        let endRow = rowIndexAt(yAbs(p));
        if (endRow < 0) endRow = yAbs(p) < rows[startRow].top ? 0 : startRow;
        const [a, b] = startRow <= endRow ? [startRow, endRow] : [endRow, startRow];
        lanes = rows.slice(a, b + 1).map((r) => r.lane);
      } else {
        lanes = prev && prev.lanes.length ? prev.lanes : this.defaultLanes;
      }
      return { t0, t1, lanes };
    };
    if (extend) {
      this.selection = normaliseSelection(selAt(p0), this.nTicks);
      this.invalidate();
      dragged = true;
    }
    this._gesture(
      canvas,
      (ev) => {
        const p = pointer(ev);
        if (!dragged && Math.abs(p.x - p0.x) < DRAG_THRESHOLD_PX) return;
        dragged = true;
        this.selection = normaliseSelection(selAt(p), this.nTicks);
        this.invalidate();
        this.emit("selection-input", { selection: this.selection });
      },
      (ev, cancelled) => {
        if (cancelled) return;
        if (dragged) {
          this.setSelection(selAt(pointer(ev)));
        } else {
          if (this.selection) this.setSelection(null);
          this.setPlayhead(p0.timeS);
          this.emit("seek", { timeS: this.playheadS });
        }
      },
    );
  }

  /**
   * @param {HTMLElement} target
   * @param {(ev: PointerEvent) => void} move
   * @param {(ev: PointerEvent, cancelled: boolean) => void} end
   */
  _gesture(target, move, end) {
    const onMove = (/** @type {PointerEvent} */ ev) => move(ev);
    const finish = (/** @type {PointerEvent} */ ev) => {
      target.removeEventListener("pointermove", onMove);
      target.removeEventListener("pointerup", finish);
      target.removeEventListener("pointercancel", finish);
      end(ev, ev.type === "pointercancel");
    };
    target.addEventListener("pointermove", onMove);
    target.addEventListener("pointerup", finish);
    target.addEventListener("pointercancel", finish);
  }

  _wireWheel() {
    this.bodyEl.addEventListener(
      "wheel",
      (e) => {
        const scale = e.deltaMode === 1 ? 16 : e.deltaMode === 2 ? this.width : 1;
        const r = this.rulerCanvas.getBoundingClientRect();
        const x = e.clientX - r.left;
        if (x < 0) return; // over the labels: let the page scroll
        e.preventDefault();
        if (e.ctrlKey || e.metaKey) {
          this.zoomBy(Math.exp(-e.deltaY * scale * 0.002), Math.min(this.width, Math.max(0, x)));
        } else {
          const d = Math.abs(e.deltaX) > Math.abs(e.deltaY) ? e.deltaX : e.deltaY;
          this.panBy(d * scale);
        }
      },
      { passive: false },
    );
  }

  _wireScrollbar() {
    const bar = this.scrollEl;
    bar.addEventListener("pointerdown", (e) => {
      if (e.button !== 0) return;
      e.preventDefault();
      bar.setPointerCapture(e.pointerId);
      const r = bar.getBoundingClientRect();
      const onThumb = e.target === this.thumbEl;
      const startX = e.clientX;
      const startS = this.startS;
      if (!onThumb) this._setStart(((e.clientX - r.left) / r.width) * this.durationS - this.visibleS / 2);
      const base = onThumb ? startS : this.startS;
      this._gesture(
        bar,
        (ev) => this._setStart(base + ((ev.clientX - startX) / r.width) * this.durationS),
        () => {},
      );
    });
  }

  destroy() {
    this._ro.disconnect();
    this.clearListeners();
    this.root.remove();
  }
}

/**
 * @param {Selection|null} sel
 * @param {number} nTicks
 * @returns {Selection|null}
 */
export function normaliseSelection(sel, nTicks) {
  if (!sel) return null;
  const t0 = Math.max(0, Math.min(nTicks - 1, Math.floor(Math.min(sel.t0, sel.t1))));
  const t1 = Math.max(t0 + 1, Math.min(nTicks, Math.ceil(Math.max(sel.t0, sel.t1))));
  return { t0, t1, lanes: [...new Set(sel.lanes)] };
}

/** A 1-2-5 step (seconds) at least `minS`. @param {number} minS */
export function niceStep(minS) {
  const steps = [0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600];
  for (const s of steps) if (s >= minS) return s;
  return 3600 * Math.ceil(minS / 3600);
}

/** @param {number} t @param {number} step */
function formatRulerTime(t, step) {
  const h = Math.floor(t / 3600);
  const m = Math.floor((t % 3600) / 60);
  const s = t % 60;
  const sec = step < 1 ? s.toFixed(1).padStart(4, "0") : String(Math.round(s)).padStart(2, "0");
  return h ? `${h}:${String(m).padStart(2, "0")}:${sec}` : `${m}:${sec}`;
}

/** @param {string} tag @param {string} cls */
function el(tag, cls) {
  const e = document.createElement(tag);
  e.className = cls;
  return e;
}
