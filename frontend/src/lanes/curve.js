/**
 * Drawing of a per-tick curve from a min/max pyramid: a filled min..max band per pixel column
 * (so peaks survive zooming out) plus its upper edge as a line.
 */

import { Columns } from "./common.js";

/**
 * @param {CanvasRenderingContext2D} ctx
 * @param {Columns} cols
 * @param {import("../data/pyramid.js").MinMaxPyramid} pyr
 * @param {import("../core/timeline.js").LaneFrame} f
 * @param {number} samplesPerS
 * @param {(value: number) => number} yOf maps a stored sample to a y coordinate
 * @param {string|CanvasGradient} stroke
 */
export function drawCurve(ctx, cols, pyr, { width, view }, samplesPerS, yOf, stroke) {
  const { min, max } = cols.fill(pyr, view, width, samplesPerS);
  ctx.strokeStyle = stroke;
  ctx.fillStyle = stroke;
  ctx.lineWidth = 1.5;
  ctx.beginPath();
  let open = false;
  for (let x = 0; x < width; x++) {
    const hi = max[x];
    if (Number.isNaN(hi)) {
      open = false;
      continue;
    }
    const yHi = yOf(hi);
    const yLo = yOf(min[x]);
    if (yLo - yHi > 1.5) ctx.fillRect(x, yHi, 1, yLo - yHi);
    if (!open) ctx.moveTo(x, yHi);
    else ctx.lineTo(x, yHi);
    ctx.lineTo(x + 1, yHi);
    open = true;
  }
  ctx.stroke();
}
