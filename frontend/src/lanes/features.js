/**
 * One lane per normalised audio feature (loudness, sharpness, booming, low_energy) with its
 * threshold line. Dragging the line is a live preview (the part of the curve above the line lights
 * up: where the feature triggers vibration); releasing it commits the threshold, which the editor
 * sends to the server (PUT /params) to re-derive the vibration.
 */

import { COLORS } from "../core/colormap.js";
import { BaseLane, areaPath, background, message } from "./common.js";

const PAD = 3;
const GRAB_PX = 6;

/**
 * @typedef {{
 *   data: () => import("../data/timeline-data.js").TimelineData|null,
 *   threshold: (name: string) => number|null,
 *   onInput: (name: string, value: number) => void,
 *   onCommit: (name: string, value: number) => void,
 *   onCancel: (name: string) => void,
 * }} FeatureLaneHooks
 */

export const FEATURE_LABELS = /** @type {Record<string, string>} */ ({
  loudness: "Loudness",
  sharpness: "Sharpness",
  booming: "Booming",
  low_energy: "Low energy",
});

/** @extends {BaseLane<FeatureLaneHooks>} */
export class FeatureLane extends BaseLane {
  /**
   * @param {string} name feature name
   * @param {FeatureLaneHooks} hooks
   */
  constructor(name, hooks) {
    const label = FEATURE_LABELS[name] || name;
    super({ id: `feature-${name}`, label, title: `${label} (normalised 0..1) and its threshold: drag the pink line (Shift: ten times finer)`, height: 46 }, hooks);
    this.name = name;
    /** @type {number|null} value shown while the line is dragged */
    this.draft = null;
    /** @type {{y: number, value: number}|null} where a threshold drag started and the value it grabbed */
    this._grab = null;
  }

  /** The threshold drawn now (the draft while dragging). */
  current() {
    return this.draft ?? this.hooks.threshold(this.name);
  }

  /** @param {number} value @param {number} height */
  yOf(value, height) {
    return height - PAD - Math.min(1, Math.max(0, value)) * (height - 2 * PAD);
  }

  /** @param {number} y @param {number} height */
  valueAt(y, height) {
    const v = (height - PAD - y) / (height - 2 * PAD);
    return Math.round(Math.min(1, Math.max(0, v)) * 100) / 100;
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").LaneFrame} f
   */
  draw(ctx, { width, height, view }) {
    background(ctx, width, height, [0.5]);
    const data = this.hooks.data();
    const pyr = data && data.featurePyr.get(this.name);
    if (!data || !pyr) {
      message(ctx, width, height, data ? "Not computed for this project" : "");
      return;
    }
    const { max } = this.cols.fill(pyr, view, width, 1 / data.tickS);
    const thr = this.current();
    areaPath(ctx, max, width, PAD, height - PAD, 255);
    ctx.fillStyle = COLORS.featureDim;
    ctx.fill();
    if (thr !== null) {
      const ty = this.yOf(thr, height);
      ctx.save();
      ctx.beginPath();
      ctx.rect(0, 0, width, ty);
      ctx.clip();
      areaPath(ctx, max, width, PAD, height - PAD, 255);
      ctx.fillStyle = this.draft !== null ? COLORS.draft : COLORS.featureHot;
      ctx.fill();
      ctx.restore();
      ctx.strokeStyle = COLORS.threshold;
      ctx.lineWidth = this.draft !== null ? 2 : 1.5;
      ctx.setLineDash([6, 4]);
      ctx.beginPath();
      ctx.moveTo(0, Math.round(ty) + 0.5);
      ctx.lineTo(width, Math.round(ty) + 0.5);
      ctx.stroke();
      ctx.setLineDash([]);
      ctx.fillStyle = COLORS.threshold;
      ctx.font = "bold 11px system-ui, sans-serif";
      ctx.textBaseline = ty < 14 ? "top" : "bottom";
      const label = thr.toFixed(2);
      const tw = ctx.measureText(label).width;
      ctx.fillText(label, width - tw - 6, ty < 14 ? ty + 2 : ty - 2);
    }
  }

  /** @param {{x: number, y: number, view: import("../core/timeline.js").TimelineView}} p */
  cursorAt(p) {
    return this._nearLine(p.y) ? "ns-resize" : null;
  }

  /** @param {number} y */
  _nearLine(y) {
    const thr = this.current();
    return thr !== null && Math.abs(y - this.yOf(thr, this.height)) <= GRAB_PX;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerDown(p) {
    if (!this._nearLine(p.y)) return false;
    const start = /** @type {number} */ (this.current());
    this._grab = { y: p.y, value: start };
    this.draft = start;
    this.hooks.onInput(this.name, this.draft);
    return true;
  }

  /**
   * The threshold a drag gives: the grabbed value moved by the pointer, a tenth as fast with Shift
   * (fine mode), in steps of 0.01 (0.001 with Shift).
   * @param {import("../core/timeline.js").LanePointer} p
   */
  _dragValue(p) {
    const grab = this._grab || { y: p.y, value: this.valueAt(p.y, this.height) };
    const fine = p.event.shiftKey;
    const v = grab.value + ((grab.y - p.y) / (this.height - 2 * PAD)) * (fine ? 0.1 : 1);
    const step = fine ? 1000 : 100;
    return Math.round(Math.min(1, Math.max(0, v)) * step) / step;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerMove(p) {
    const v = this._dragValue(p);
    if (v === this.draft) return;
    this.draft = v;
    this.hooks.onInput(this.name, v);
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerUp(p) {
    const v = this._dragValue(p);
    this.draft = null;
    this._grab = null;
    this.hooks.onCommit(this.name, v);
  }

  pointerCancel() {
    this.draft = null;
    this._grab = null;
    this.hooks.onCancel(this.name);
  }
}
