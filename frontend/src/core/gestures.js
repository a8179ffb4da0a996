/**
 * The pointer and wheel gestures common to every lane: scrubbing on the ruler, a lane's own
 * gesture when it claims one, otherwise click-to-seek and drag-to-select; panning (middle button,
 * Alt+drag, wheel), zooming at the pointer (Ctrl+wheel) and the scrollbar.
 */

import { allEditRows, normaliseSelection } from "./selection.js";

const DRAG_THRESHOLD_PX = 3;

/**
 * @typedef {import("./timeline.js").TimelineView} TimelineView
 * @typedef {import("./timeline.js").LanePointer} LanePointer
 * @typedef {import("./timeline.js").LaneEntry} LaneEntry
 * @typedef {import("./timeline.js").Selection} Selection
 */

/** @param {TimelineView} view */
export function wireGestures(view) {
  wireRuler(view);
  wireLanes(view);
  wireWheel(view);
  wireScrollbar(view);
}

/**
 * Call `fn` on each primary-button press on `target`, with the pointer captured.
 * @param {HTMLElement} target
 * @param {(e: PointerEvent) => void} fn
 */
function onPrimaryPress(target, fn) {
  target.addEventListener("pointerdown", (e) => {
    if (e.button !== 0) return;
    e.preventDefault();
    target.setPointerCapture(e.pointerId);
    fn(e);
  });
}

/**
 * Follow one captured pointer until it is released or cancelled.
 * @param {HTMLElement} target
 * @param {(ev: PointerEvent) => void} move
 * @param {(ev: PointerEvent, cancelled: boolean) => void} end
 */
function gesture(target, move, end) {
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

/** The ruler scrubs while dragged (`scrub`) and seeks where released (`seek`). @param {TimelineView} view */
function wireRuler(view) {
  const c = view.rulerCanvas;
  const at = (/** @type {PointerEvent} */ ev) => view.clampTime(view.xToTime(ev.offsetX));
  const scrub = (/** @type {PointerEvent} */ ev) => {
    view.setPlayhead(at(ev));
    view.emit("scrub", { timeS: view.playheadS });
  };
  onPrimaryPress(c, (e) => {
    scrub(e);
    gesture(c, scrub, (ev) => {
      view.setPlayhead(at(ev));
      view.emit("seek", { timeS: view.playheadS });
    });
  });
}

/**
 * The lane canvas an event happened on, with its registry entry; null off the lanes.
 * @param {TimelineView} view
 * @param {Event} e
 */
function laneUnder(view, e) {
  const canvas = e.target;
  if (!(canvas instanceof HTMLCanvasElement)) return null;
  const entry = view.lanes.find((l) => l.canvas === canvas);
  return entry ? { canvas, entry } : null;
}

/** @param {TimelineView} view */
function wireLanes(view) {
  const host = view.lanesEl;
  host.addEventListener("pointerdown", (e) => {
    const hit = laneUnder(view, e);
    if (!hit) return;
    const { canvas, entry } = hit;
    view.root.focus({ preventScroll: true });
    /** @returns {LanePointer} */
    const pointer = (/** @type {PointerEvent} */ ev) => {
      const r = canvas.getBoundingClientRect();
      const x = ev.clientX - r.left;
      const y = ev.clientY - r.top;
      return { x, y, timeS: view.clampTime(view.xToTime(x)), tick: view.xToTick(x), event: ev, view };
    };
    const p0 = pointer(e);
    canvas.setPointerCapture(e.pointerId);
    e.preventDefault();
    // Middle button or Alt+drag pans whatever the tool.
    if (e.button === 1 || (e.button === 0 && e.altKey)) {
      gesture(canvas, (ev) => view.panBy(-(ev.movementX || 0)), () => {});
      return;
    }
    if (e.button !== 0) return;
    const lane = entry.lane;
    if (lane.pointerDown && lane.pointerDown(p0)) {
      gesture(
        canvas,
        (ev) => lane.pointerMove && lane.pointerMove(pointer(ev)),
        (ev, cancelled) => {
          if (cancelled) lane.pointerCancel && lane.pointerCancel(pointer(ev));
          else lane.pointerUp && lane.pointerUp(pointer(ev));
        },
      );
      return;
    }
    selectGesture(view, canvas, entry, p0, pointer);
  });
  host.addEventListener("dblclick", (e) => {
    const hit = laneUnder(view, e);
    if (!hit || !hit.entry.lane.dblclick) return;
    const x = e.offsetX;
    hit.entry.lane.dblclick({
      x, y: e.offsetY, timeS: view.clampTime(view.xToTime(x)), tick: view.xToTick(x),
      event: /** @type {PointerEvent} */ (/** @type {unknown} */ (e)), view,
    });
  });
  host.addEventListener("pointermove", (e) => {
    if (e.buttons) return;
    const hit = laneUnder(view, e);
    if (!hit) return;
    const { canvas, entry } = hit;
    const cur = entry.lane.cursorAt ? entry.lane.cursorAt({ x: e.offsetX, y: e.offsetY, view }) : null;
    canvas.style.cursor = cur || (view.tool === "pencil" && entry.lane.editRows ? "crosshair" : "default");
  });
}

/**
 * Drag on a lane: a click seeks, a drag selects a tick range on the edit rows it crosses.
 * @param {TimelineView} view
 * @param {HTMLCanvasElement} canvas
 * @param {LaneEntry} entry
 * @param {LanePointer} p0
 * @param {(ev: PointerEvent) => LanePointer} pointer
 */
function selectGesture(view, canvas, entry, p0, pointer) {
  const rows = allEditRows(view.lanes);
  const yAbs = (/** @type {LanePointer} */ p) => entry.row.offsetTop + p.y;
  const rowIndexAt = (/** @type {number} */ y) => rows.findIndex((r) => y >= r.top && y < r.bottom);
  const startRow = rowIndexAt(yAbs(p0));
  const prev = view.selection;
  const extend = p0.event.shiftKey && prev;
  const anchorTick = extend ? (p0.tick < prev.t0 ? prev.t1 : prev.t0) : p0.tick;
  let dragged = false;
  // Edges snap to shot boundaries a few pixels away, unless Alt is held while dragging.
  const snap = (/** @type {number} */ t, /** @type {LanePointer} */ p) => (view.snapTick && !p.event.altKey ? view.snapTick(t) : t);
  /** @param {LanePointer} p @returns {Selection} */
  const selAt = (p) => {
    let t0 = Math.min(anchorTick, p.tick);
    let t1 = Math.max(anchorTick, p.tick) + 1;
    const s0 = snap(t0, p);
    const s1 = snap(t1, p);
    if (s1 > s0) [t0, t1] = [s0, s1];
    /** @type {string[]} */
    let lanes;
    if (startRow >= 0) {
      let endRow = rowIndexAt(yAbs(p));
      if (endRow < 0) endRow = yAbs(p) < rows[startRow].top ? 0 : startRow;
      const [a, b] = startRow <= endRow ? [startRow, endRow] : [endRow, startRow];
      lanes = rows.slice(a, b + 1).map((r) => r.lane);
    } else {
      lanes = prev && prev.lanes.length ? prev.lanes : view.defaultLanes;
    }
    return { t0, t1, lanes };
  };
  if (extend) {
    view.selection = normaliseSelection(selAt(p0), view.nTicks);
    view.invalidate();
    dragged = true;
  }
  gesture(
    canvas,
    (ev) => {
      const p = pointer(ev);
      if (!dragged && Math.abs(p.x - p0.x) < DRAG_THRESHOLD_PX) return;
      dragged = true;
      view.selection = normaliseSelection(selAt(p), view.nTicks);
      view.invalidate();
      view.emit("selection-input", { selection: view.selection });
    },
    (ev, cancelled) => {
      if (cancelled) return;
      if (dragged) {
        view.setSelection(selAt(pointer(ev)));
      } else {
        if (view.selection) view.setSelection(null);
        view.setPlayhead(p0.timeS);
        view.emit("seek", { timeS: view.playheadS });
      }
    },
  );
}

/** Wheel pans; Ctrl+wheel (a pinch) zooms at the pointer. @param {TimelineView} view */
function wireWheel(view) {
  view.bodyEl.addEventListener(
    "wheel",
    (e) => {
      const scale = e.deltaMode === 1 ? 16 : e.deltaMode === 2 ? view.width : 1;
      const r = view.rulerCanvas.getBoundingClientRect();
      const x = e.clientX - r.left;
      if (x < 0) return; // over the labels: let the page scroll
      e.preventDefault();
      if (e.ctrlKey || e.metaKey) {
        view.zoomBy(Math.exp(-e.deltaY * scale * 0.002), Math.min(view.width, Math.max(0, x)));
      } else {
        const d = Math.abs(e.deltaX) > Math.abs(e.deltaY) ? e.deltaX : e.deltaY;
        view.panBy(d * scale);
      }
    },
    { passive: false },
  );
}

/** Drag the thumb to scroll; a press beside it centres the view there first. @param {TimelineView} view */
function wireScrollbar(view) {
  const bar = view.scrollEl;
  onPrimaryPress(bar, (e) => {
    const r = bar.getBoundingClientRect();
    const onThumb = e.target === view.thumbEl;
    const startX = e.clientX;
    const startS = view.startS;
    if (!onThumb) view.scrollTo(((e.clientX - r.left) / r.width) * view.durationS - view.visibleS / 2);
    const base = onThumb ? startS : view.startS;
    gesture(bar, (ev) => view.scrollTo(base + ((ev.clientX - startX) / r.width) * view.durationS), () => {});
  });
}
