/**
 * What every lane shares: the fields the timeline core reads (core/timeline.js `Lane`),
 * per-pixel-column envelopes read from a pyramid, and plain backgrounds.
 */

import { COLORS } from "../core/colormap.js";

/**
 * A lane's id, label, tooltip and height, its hooks into the editor, and its column buffers.
 * @template H
 */
export class BaseLane {
  /**
   * @param {{id: string, label: string, title: string, height: number}} spec
   * @param {H} hooks
   */
  constructor({ id, label, title, height }, hooks) {
    this.id = id;
    this.label = label;
    this.title = title;
    this.height = height;
    this.hooks = hooks;
    this.cols = new Columns();
  }
}

export class Columns {
  constructor() {
    this.min = new Float32Array(0);
    this.max = new Float32Array(0);
  }

  /**
   * Fill min/max per pixel column of the visible range.
   * @param {import("../data/pyramid.js").MinMaxPyramid} pyr
   * @param {import("../core/timeline.js").TimelineView} view
   * @param {number} width
   * @param {number} samplesPerS samples per second of `pyr` (10 for ticks)
   */
  fill(pyr, view, width, samplesPerS) {
    if (this.min.length < width) {
      this.min = new Float32Array(width);
      this.max = new Float32Array(width);
    }
    pyr.fillColumns(view.startS * samplesPerS, samplesPerS / view.pxPerS, width, this.min, this.max);
    return this;
  }
}

/**
 * @param {CanvasRenderingContext2D} ctx
 * @param {number} width
 * @param {number} height
 * @param {number[]} fractions y positions (0 top .. 1 bottom) of faint grid lines
 */
export function background(ctx, width, height, fractions = []) {
  ctx.fillStyle = COLORS.laneBg;
  ctx.fillRect(0, 0, width, height);
  if (!fractions.length) return;
  ctx.strokeStyle = COLORS.grid;
  ctx.lineWidth = 1;
  ctx.beginPath();
  for (const f of fractions) {
    const y = Math.round(f * height) + 0.5;
    ctx.moveTo(0, y);
    ctx.lineTo(width, y);
  }
  ctx.stroke();
}

/**
 * @param {CanvasRenderingContext2D} ctx
 * @param {number} width
 * @param {number} height
 * @param {string} text
 */
export function message(ctx, width, height, text) {
  ctx.fillStyle = COLORS.text;
  ctx.font = "12px system-ui, sans-serif";
  ctx.textBaseline = "middle";
  ctx.fillText(text, 8, height / 2);
}

/**
 * Fill the area under a 0..1 envelope (per-column maxima) between `top` and `bottom`.
 * @param {CanvasRenderingContext2D} ctx
 * @param {Float32Array} max
 * @param {number} width
 * @param {number} top
 * @param {number} bottom
 * @param {number} [scale] divide values by this (255 for byte tracks)
 */
export function areaPath(ctx, max, width, top, bottom, scale = 1) {
  const h = bottom - top;
  ctx.beginPath();
  let open = false;
  for (let x = 0; x < width; x++) {
    const v = max[x];
    if (Number.isNaN(v)) {
      if (open) {
        ctx.lineTo(x, bottom);
        open = false;
      }
      continue;
    }
    const y = bottom - (v / scale) * h;
    if (!open) {
      ctx.moveTo(x, bottom);
      open = true;
    }
    ctx.lineTo(x, y);
    ctx.lineTo(x + 1, y);
  }
  if (open) ctx.lineTo(width, bottom);
  ctx.closePath();
}
