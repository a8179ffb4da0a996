/**
 * Lane heights the user sets: a handle on each lane's lower edge (drag it; arrow keys move it by
 * 8 px; a double-click gives the lane its own height back). The timeline emits `lane-height` when a
 * change ends; keeping heights is the editor's (pages/editor/lanes.js).
 */

import { h } from "./dom.js";

/** Lane heights allowed, CSS px. */
export const LANE_HEIGHT_RANGE = /** @type {const} */ ([24, 480]);
const KEY_STEP_PX = 8;

/** @param {number} px */
export function clampLaneHeight(px) {
  return Math.round(Math.min(LANE_HEIGHT_RANGE[1], Math.max(LANE_HEIGHT_RANGE[0], px)));
}

/**
 * The resize handle of one lane's row.
 * @param {import("./timeline.js").TimelineView} view
 * @param {import("./timeline.js").Lane} lane
 * @param {number} ownHeight the lane's height before any change (restored by a double-click)
 */
export function resizeHandle(view, lane, ownHeight) {
  const handle = h("div", {
    class: "tl-resize", role: "separator", tabindex: "0", "aria-orientation": "horizontal",
    "aria-label": `Height of the ${lane.label} lane: drag or use the arrow keys`, "data-testid": `lane-resize-${lane.id}`,
  });
  const set = (/** @type {number} */ px, /** @type {boolean} */ done) => {
    view.setLaneHeight(lane.id, px);
    handle.setAttribute("aria-valuenow", String(lane.height));
    if (done) view.emit("lane-height", { id: lane.id, height: lane.height });
  };
  handle.addEventListener("pointerdown", (e) => {
    if (e.button !== 0) return;
    e.preventDefault();
    e.stopPropagation();
    handle.setPointerCapture(e.pointerId);
    const y0 = e.clientY;
    const h0 = lane.height;
    const move = (/** @type {PointerEvent} */ ev) => set(h0 + ev.clientY - y0, false);
    const end = (/** @type {PointerEvent} */ ev) => {
      handle.removeEventListener("pointermove", move);
      handle.removeEventListener("pointerup", end);
      handle.removeEventListener("pointercancel", end);
      set(ev.type === "pointercancel" ? h0 : h0 + ev.clientY - y0, true);
    };
    handle.addEventListener("pointermove", move);
    handle.addEventListener("pointerup", end);
    handle.addEventListener("pointercancel", end);
  });
  handle.addEventListener("dblclick", () => set(ownHeight, true));
  handle.addEventListener("keydown", (e) => {
    const step = e.key === "ArrowDown" ? KEY_STEP_PX : e.key === "ArrowUp" ? -KEY_STEP_PX : 0;
    if (!step) return;
    e.preventDefault();
    e.stopPropagation();
    set(lane.height + step, true);
  });
  return handle;
}
