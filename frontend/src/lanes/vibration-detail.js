/**
 * One actuator's vibration as a curve, large enough to draw on: with the pencil tool a drag writes
 * per-tick values (y = intensity) and becomes one `pencil` op on release.
 */

import { COLORS } from "../core/colormap.js";
import { BaseLane, background, message } from "./common.js";
import { drawCurve } from "./curve.js";
import { PencilStroke } from "./pencil.js";

const PAD = 4;

/**
 * @typedef {{data: () => import("../data/timeline-data.js").TimelineData|null, actuatorIds: string[],
 *   onPencil: (op: Record<string, any>) => void, onChange: () => void}} DetailHooks actuator ids in the timeline's order
 */

/** @extends {BaseLane<DetailHooks>} */
export class VibrationDetailLane extends BaseLane {
  /** @param {DetailHooks} hooks */
  constructor(hooks) {
    super({ id: "detail", label: "Detail", title: "One actuator's intensity as a curve; draw on it with the pencil tool", height: 64 }, hooks);
    this.actuator = hooks.actuatorIds[0];
    /** @type {PencilStroke|null} */
    this.stroke = null;
  }

  /** @param {string} id */
  setActuator(id) {
    if (!this.hooks.actuatorIds.includes(id)) return;
    this.actuator = id;
    if (this.select) this.select.value = id;
    this.hooks.onChange();
  }

  /** @param {HTMLElement} label */
  decorateLabel(label) {
    const select = document.createElement("select");
    select.className = "tl-select";
    select.setAttribute("aria-label", "Actuator shown in the detail lane");
    select.setAttribute("data-testid", "detail-actuator");
    for (const id of this.hooks.actuatorIds) select.add(new Option(id, id));
    select.value = this.actuator;
    select.addEventListener("change", () => this.setActuator(select.value));
    this.select = select;
    label.append(select);
  }

  /** @param {number} height */
  editRows(height) {
    return [{ lane: this.actuator, y0: 0, y1: height }];
  }

  /** @param {number} v 0..1 */
  yOf(v) {
    return this.height - PAD - v * (this.height - 2 * PAD);
  }

  /** @param {number} y */
  valueAt(y) {
    return Math.min(1, Math.max(0, (this.height - PAD - y) / (this.height - 2 * PAD)));
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").LaneFrame} f
   */
  draw(ctx, f) {
    background(ctx, f.width, f.height, [0.25, 0.5, 0.75]);
    const data = this.hooks.data();
    if (!data) {
      message(ctx, f.width, f.height, "");
      return;
    }
    const pyr = data.vibrationPyr[this.hooks.actuatorIds.indexOf(this.actuator)];
    drawCurve(ctx, this.cols, pyr, f, 1 / data.tickS, (b) => this.yOf(b / 255), COLORS.vibration);
    if (this.stroke) this.stroke.draw(ctx, f.view, (v) => this.yOf(v));
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerDown(p) {
    if (p.view.tool !== "pencil" || !this.hooks.data()) return false;
    this.stroke = new PencilStroke(this.actuator, p.tick, this.valueAt(p.y));
    p.view.invalidate(this.id);
    return true;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerMove(p) {
    if (!this.stroke) return;
    this.stroke.add(p.tick, this.valueAt(p.y));
    p.view.invalidate(this.id);
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerUp(p) {
    if (!this.stroke) return;
    this.stroke.add(p.tick, this.valueAt(p.y));
    const op = this.stroke.toOp(3);
    this.hooks.onPencil(op);
  }

  /** Drop the preview stroke (after the op is applied or failed). */
  clearStroke() {
    this.stroke = null;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerCancel(p) {
    this.stroke = null;
    p.view.invalidate(this.id);
  }
}
