/**
 * The editor's keyboard: the shortcut handler and the "Keys" menu that lists the shortcuts.
 * Text fields keep their own keys; STOP on Escape is the chair part's (./chair.js), since it must
 * work wherever the focus is.
 */

import { h } from "../../core/dom.js";
import { clearOp } from "../../data/edit-ops.js";

/** Zoom factor of one zoom step (the + and - keys and buttons). */
export const ZOOM_STEP = 1.5;

const KEYS = [
  ["Space", "play / pause"], ["← →", "step one tick (Shift: one second)"], ["Home / End", "start / end"],
  ["+ / − / 0", "zoom in / out / whole film"], ["Ctrl+wheel, pinch", "zoom at the pointer"], ["Wheel", "pan"],
  ["Alt+drag, middle drag", "pan"], ["Drag on lanes", "select a range (across heat-map rows: several actuators)"],
  ["Alt while dragging", "no snapping to shot boundaries"],
  ["Click / Shift-click a shot", "select it / add it (Shots lane or panel); double-click: play it"],
  ["S / M", "split the shot at the playhead / merge it with the next"],
  ["Ctrl+Z / Ctrl+Shift+Z", "undo / redo"], ["Ctrl+C / Ctrl+V", "copy / paste at the playhead (onto selected shots: fitted to each)"],
  ["Delete", "clear the selection, or delete the selected marker"], ["Escape", "stop the chair (when connected); drop the selection or the points"],
];

/** The "Keys" menu of the transport bar. */
export function keysMenu() {
  return h(
    "details",
    { class: "menu", "data-testid": "keys-menu" },
    h("summary", { class: "btn", "aria-label": "Keyboard and mouse shortcuts" }, "Keys"),
    h("dl", { class: "menu-list keys-list" }, ...KEYS.flatMap(([k, what]) => [h("dt", {}, k), h("dd", {}, what)])),
  );
}

/**
 * Handle one keydown on the document.
 * @param {import("./shell.js").EditorPage} page
 * @param {KeyboardEvent} e
 */
export function onEditorKey(page, e) {
  if (page.disposed || document.querySelector("dialog[open]") || keptByTarget(e)) return;
  const mod = e.ctrlKey || e.metaKey;
  const handled = mod ? editKey(page, e) : viewKey(page, e);
  if (handled) e.preventDefault();
}

/**
 * Text fields keep every key (their own undo included); sliders keep their arrow keys.
 * @param {KeyboardEvent} e
 */
function keptByTarget(e) {
  const t = /** @type {HTMLElement} */ (e.target);
  const tag = t && t.tagName;
  const inputType = tag === "INPUT" ? /** @type {HTMLInputElement} */ (t).type : "";
  if (t && (t.isContentEditable || tag === "TEXTAREA" || tag === "SELECT" || (tag === "INPUT" && !["range", "checkbox", "button"].includes(inputType)))) return true;
  return inputType === "range" && /^(Arrow|Home|End|Page)/.test(e.key);
}

/**
 * Ctrl (Cmd) shortcuts: undo, redo, copy, paste. Returns whether the key was used.
 * @param {import("./shell.js").EditorPage} page
 * @param {KeyboardEvent} e
 */
function editKey(page, e) {
  const edits = page.edits;
  if (e.key === "z" || e.key === "Z") {
    if (e.shiftKey) edits.redo();
    else edits.undo();
  } else if (e.key === "y") {
    edits.redo();
  } else if (e.key === "c") {
    edits.copy();
  } else if (e.key === "v") {
    edits.paste();
  } else {
    return false;
  }
  return true;
}

/**
 * Plain keys: playback, stepping, zoom, shot split and merge, Delete and Escape. Returns whether the key was used.
 * @param {import("./shell.js").EditorPage} page
 * @param {KeyboardEvent} e
 */
function viewKey(page, e) {
  const tl = page.timeline;
  const media = page.media;
  const markers = page.markers;
  const tick = page.tickS;
  if (e.key === " ") {
    media.togglePlay();
  } else if (e.key === "ArrowLeft" || e.key === "ArrowRight") {
    const step = e.shiftKey ? 1 : tick;
    const dir = e.key === "ArrowLeft" ? -1 : 1;
    const base = Math.round(media.player.currentTime / tick) * tick;
    media.seek(base + dir * step);
  } else if (e.key === "Home") {
    media.seek(0);
  } else if (e.key === "End") {
    media.seek(tl.durationS);
  } else if (e.key === "+" || e.key === "=") {
    tl.zoomBy(ZOOM_STEP);
  } else if (e.key === "-" || e.key === "_") {
    tl.zoomBy(1 / ZOOM_STEP);
  } else if (e.key === "0") {
    tl.fit();
  } else if ((e.key === "s" || e.key === "S") && !e.altKey) {
    page.shots.split();
  } else if ((e.key === "m" || e.key === "M") && !e.altKey) {
    page.shots.merge();
  } else if (e.key === "Delete" || e.key === "Backspace") {
    if (markers.selected) markers.remove(markers.selected);
    else if (tl.selection) page.edits.selectionOp((sel) => clearOp(sel));
    else return false;
  } else if (e.key === "Escape") {
    if (page.edits.points.length) page.edits.setPoints([]);
    else if (tl.selection) tl.setSelection(null);
    else if (markers.selected) markers.select(null);
    else return false;
  } else {
    return false;
  }
  return true;
}
