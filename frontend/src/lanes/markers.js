/**
 * Markers: labelled points in time. Drag a flag to move it (live while dragging, one
 * `marker_update` op on release), click it to select it and move the playhead there, double-click
 * it to rename, double-click empty space to add one.
 */

import { COLORS } from "../core/colormap.js";
import { BaseLane, background } from "./common.js";

const HIT_PX = 6;

/**
 * @typedef {{id: string, t_s: number, label: string}} Marker
 * @typedef {{
 *   markers: () => Marker[],
 *   selected: () => string|null,
 *   onSelect: (id: string|null) => void,
 *   onMove: (id: string, t_s: number) => void,
 *   onAdd: (t_s: number) => void,
 *   onRename: (id: string) => void,
 * }} MarkerHooks
 */

/** @extends {BaseLane<MarkerHooks>} */
export class MarkersLane extends BaseLane {
  /** @param {MarkerHooks} hooks */
  constructor(hooks) {
    super({ id: "markers", label: "Markers", title: "Markers: double-click to add, drag to move, double-click a marker to rename", height: 28 }, hooks);
    /** @type {{id: string, t_s: number, moved: boolean}|null} */
    this.drag = null;
  }

  /** @param {Marker} m */
  _time(m) {
    return this.drag && this.drag.id === m.id ? this.drag.t_s : m.t_s;
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").LaneFrame} f
   */
  draw(ctx, { width, height, view }) {
    background(ctx, width, height);
    const selected = this.hooks.selected();
    ctx.font = "11px system-ui, sans-serif";
    ctx.textBaseline = "middle";
    for (const m of this.hooks.markers()) {
      const x = Math.round(view.timeToX(this._time(m))) + 0.5;
      if (x < -200 || x > width + 2) continue;
      const on = m.id === selected;
      ctx.strokeStyle = on ? "#fff" : COLORS.marker;
      ctx.fillStyle = on ? "#fff" : COLORS.marker;
      ctx.lineWidth = on ? 2 : 1;
      ctx.beginPath();
      ctx.moveTo(x, 2);
      ctx.lineTo(x, height);
      ctx.stroke();
      ctx.beginPath();
      ctx.moveTo(x, 2);
      ctx.lineTo(x + 7, 6);
      ctx.lineTo(x, 10);
      ctx.fill();
      ctx.fillText(m.label, x + 10, height / 2 + 3);
    }
  }

  /** @param {number} x @param {import("../core/timeline.js").TimelineView} view */
  _hit(x, view) {
    let best = null;
    let bestD = HIT_PX + 1;
    for (const m of this.hooks.markers()) {
      const d = Math.abs(view.timeToX(m.t_s) - x);
      if (d < bestD) {
        best = m;
        bestD = d;
      }
    }
    return best;
  }

  /** @param {{x: number, y: number, view: import("../core/timeline.js").TimelineView}} p */
  cursorAt(p) {
    return this._hit(p.x, p.view) ? "ew-resize" : null;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerDown(p) {
    const m = this._hit(p.x, p.view);
    if (!m) return false;
    this.drag = { id: m.id, t_s: m.t_s, moved: false };
    this.hooks.onSelect(m.id);
    return true;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerMove(p) {
    if (!this.drag) return;
    this.drag.t_s = Math.round(p.timeS * 10) / 10;
    this.drag.moved = true;
    p.view.invalidate(this.id);
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerUp(p) {
    const d = this.drag;
    if (!d) return;
    if (d.moved) {
      this.hooks.onMove(d.id, d.t_s);
      // The flag stays at its dragged place until the saved marker list arrives.
    } else {
      this.drag = null;
      p.view.setPlayhead(d.t_s);
      p.view.emit("seek", { timeS: d.t_s });
    }
  }

  /** Forget the local drag position (the saved list now has the marker where it was dropped). */
  settle() {
    this.drag = null;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerCancel(p) {
    this.drag = null;
    p.view.invalidate(this.id);
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  dblclick(p) {
    const m = this._hit(p.x, p.view);
    if (m) this.hooks.onRename(m.id);
    else this.hooks.onAdd(Math.round(p.timeS * 10) / 10);
  }
}
