/**
 * The temperature lane (degrees C): the curve the chair plays (after its clamp and slew limit,
 * computed by the server) over the target edits change, the neutral line and the chair's limits.
 * Two editing gestures:
 * - pencil tool: draw per-tick temperatures (one `pencil` op on release);
 * - points tool: place and drag breakpoints (Shift+click removes one); the editor turns the draft
 *   into one `temp_points` op when the user applies it.
 */

import { COLORS } from "../core/colormap.js";
import { BaseLane, background, message } from "./common.js";
import { drawCurve } from "./curve.js";
import { PencilStroke } from "./pencil.js";

const PAD = 5;
const HIT_PX = 7;

/**
 * @typedef {{
 *   data: () => import("../data/timeline-data.js").TimelineData|null,
 *   range: () => {lo: number, hi: number, neutral: number},
 *   played: () => import("../data/played-temperature.js").PlayedTemperature|null,
 *   onPencil: (op: Record<string, any>) => void,
 *   onPointsChange: (points: Array<[number, number]>) => void,
 * }} TemperatureHooks
 */

/** @extends {BaseLane<TemperatureHooks>} */
export class TemperatureLane extends BaseLane {
  /** @param {TemperatureHooks} hooks */
  constructor(hooks) {
    const title = "Temperature in °C: the chair's curve in colour (clamped and slew-limited by the chair), the target in grey, "
      + "neutral dashed, the chair's limits dotted; pencil draws, points tool places breakpoints";
    super({ id: "temperature", label: "Temperature", title, height: 72 }, hooks);
    /** @type {PencilStroke|null} */
    this.stroke = null;
    /** @type {Array<[number, number]>} draft breakpoints [tick, C], sorted by tick */
    this.points = [];
    /** @type {number} index of the point being dragged */
    this._dragging = -1;
  }

  /** @param {number} height */
  editRows(height) {
    return [{ lane: "temperature", y0: 0, y1: height }];
  }

  /** @param {number} c */
  yOf(c) {
    const { lo, hi } = this.hooks.range();
    return this.height - PAD - ((c - lo) / Math.max(1e-6, hi - lo)) * (this.height - 2 * PAD);
  }

  /** @param {number} y */
  valueAt(y) {
    const { lo, hi } = this.hooks.range();
    const c = lo + ((this.height - PAD - y) / (this.height - 2 * PAD)) * (hi - lo);
    return Math.round(Math.min(hi, Math.max(lo, c)) * 10) / 10;
  }

  /**
   * The target (thin, grey), what the chair plays (the coloured curve, once loaded), the neutral
   * line (dashed) and the chair's limits (dotted, labelled).
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").LaneFrame} f
   */
  draw(ctx, f) {
    const { width, height, view } = f;
    background(ctx, width, height);
    const data = this.hooks.data();
    if (!data) {
      message(ctx, width, height, "");
      return;
    }
    const { lo, hi, neutral } = this.hooks.range();
    ctx.fillStyle = COLORS.text;
    ctx.font = "10px system-ui, sans-serif";
    ctx.textBaseline = "top";
    ctx.fillText(`${hi.toFixed(0)} °C`, 4, 2);
    ctx.textBaseline = "bottom";
    ctx.fillText(`${lo.toFixed(0)} °C`, 4, height - 1);
    this._hLine(ctx, width, neutral, COLORS.tempNeutral, [4, 4]);
    const played = this.hooks.played();
    if (played && played.revision === data.revision) {
      this._drawLimits(ctx, width, played);
      drawCurve(ctx, this.cols, data.temperaturePyr, f, 1 / data.tickS, (c) => this.yOf(c), COLORS.tempTarget);
      const grad = ctx.createLinearGradient(0, this.yOf(hi), 0, this.yOf(lo));
      grad.addColorStop(0, "#f87171");
      grad.addColorStop(Math.min(1, Math.max(0, (hi - neutral) / (hi - lo))), "#cbd5e1");
      grad.addColorStop(1, "#60a5fa");
      drawCurve(ctx, this.cols, played.pyr, f, 1 / data.tickS, (c) => this.yOf(c), grad);
    } else {
      drawCurve(ctx, this.cols, data.temperaturePyr, f, 1 / data.tickS, (c) => this.yOf(c), COLORS.tempTarget);
    }
    if (this.stroke) this.stroke.draw(ctx, view, (c) => this.yOf(c));
    if (this.points.length) this._drawPoints(ctx, view);
  }

  /**
   * A horizontal line at a temperature, when it lies on the lane.
   * @param {CanvasRenderingContext2D} ctx @param {number} width @param {number} c
   * @param {string} color @param {number[]} dash
   */
  _hLine(ctx, width, c, color, dash) {
    const y = Math.round(this.yOf(c)) + 0.5;
    if (y < 0 || y > this.height) return null;
    ctx.strokeStyle = color;
    ctx.setLineDash(dash);
    ctx.beginPath();
    ctx.moveTo(0, y);
    ctx.lineTo(width, y);
    ctx.stroke();
    ctx.setLineDash([]);
    return y;
  }

  /**
   * The chair's safe range as dotted lines with their labels (right-aligned).
   * @param {CanvasRenderingContext2D} ctx @param {number} width
   * @param {import("../data/played-temperature.js").PlayedTemperature} played
   */
  _drawLimits(ctx, width, played) {
    ctx.save();
    ctx.font = "10px system-ui, sans-serif";
    ctx.textAlign = "right";
    for (const [c, text] of [[played.maxC, "chair max"], [played.minC, "chair min"]]) {
      const y = this._hLine(ctx, width, /** @type {number} */ (c), COLORS.tempLimit, [1, 3]);
      if (y === null) continue;
      ctx.fillStyle = COLORS.tempLimit;
      ctx.textBaseline = y < 12 ? "top" : "bottom";
      ctx.fillText(`${text} ${Number(c).toFixed(0)} °C`, width - 4, y < 12 ? y + 1 : y - 1);
    }
    ctx.restore();
  }

  /**
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../core/timeline.js").TimelineView} view
   */
  _drawPoints(ctx, view) {
    ctx.save();
    ctx.strokeStyle = COLORS.draft;
    ctx.fillStyle = COLORS.draft;
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    this.points.forEach(([t, c], i) => {
      const x = view.tickToX(t + 0.5);
      const y = this.yOf(c);
      if (i === 0) ctx.moveTo(x, y);
      else ctx.lineTo(x, y);
    });
    ctx.stroke();
    for (const [t, c] of this.points) {
      ctx.beginPath();
      ctx.arc(view.tickToX(t + 0.5), this.yOf(c), 4, 0, Math.PI * 2);
      ctx.fill();
    }
    ctx.restore();
  }

  /** @param {number} x @param {number} y @param {import("../core/timeline.js").TimelineView} view */
  _hit(x, y, view) {
    return this.points.findIndex(([t, c]) => Math.hypot(view.tickToX(t + 0.5) - x, this.yOf(c) - y) <= HIT_PX);
  }

  /** @param {{x: number, y: number, view: import("../core/timeline.js").TimelineView}} p */
  cursorAt(p) {
    if (p.view.tool === "points") return this._hit(p.x, p.y, p.view) >= 0 ? "grab" : "copy";
    if (p.view.tool === "pencil") return "crosshair";
    return null;
  }

  /** @param {Array<[number, number]>} points */
  setPoints(points) {
    this.points = [...points].sort((a, b) => a[0] - b[0]);
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerDown(p) {
    if (!this.hooks.data()) return false;
    if (p.view.tool === "pencil") {
      this.stroke = new PencilStroke("temperature", p.tick, this.valueAt(p.y));
      p.view.invalidate(this.id);
      return true;
    }
    if (p.view.tool !== "points") return false;
    const hit = this._hit(p.x, p.y, p.view);
    if (hit >= 0 && p.event.shiftKey) {
      this.points.splice(hit, 1);
      this._dragging = -1;
    } else if (hit >= 0) {
      this._dragging = hit;
    } else {
      this.points = this.points.filter(([t]) => t !== p.tick);
      this.points.push([p.tick, this.valueAt(p.y)]);
      this.setPoints(this.points);
      this._dragging = this.points.findIndex(([t]) => t === p.tick);
    }
    this.hooks.onPointsChange(this.points);
    p.view.invalidate(this.id);
    return true;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerMove(p) {
    if (this.stroke) {
      this.stroke.add(p.tick, this.valueAt(p.y));
      p.view.invalidate(this.id);
      return;
    }
    if (this._dragging < 0) return;
    const moved = /** @type {[number, number]} */ ([p.tick, this.valueAt(p.y)]);
    const others = this.points.filter((_, i) => i !== this._dragging && _[0] !== p.tick);
    others.push(moved);
    this.setPoints(others);
    this._dragging = this.points.indexOf(moved);
    this.hooks.onPointsChange(this.points);
    p.view.invalidate(this.id);
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerUp(p) {
    if (this.stroke) {
      this.stroke.add(p.tick, this.valueAt(p.y));
      this.hooks.onPencil(this.stroke.toOp(2));
      return;
    }
    this._dragging = -1;
  }

  /** @param {import("../core/timeline.js").LanePointer} p */
  pointerCancel(p) {
    this.stroke = null;
    this._dragging = -1;
    p.view.invalidate(this.id);
  }

  clearStroke() {
    this.stroke = null;
  }
}
