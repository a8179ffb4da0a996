/**
 * The selection: a tick range [t0, t1) on a set of edit lanes. Pure helpers the timeline core
 * uses to clamp it, to find the edit rows a drag crosses, and to draw it over a lane.
 */

/**
 * @typedef {import("./timeline.js").Lane} Lane
 * @typedef {import("./timeline.js").Selection} Selection
 */

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

/**
 * Edit rows of every visible lane, top to bottom, with y relative to the lanes container.
 * @param {{lane: Lane, row: HTMLElement}[]} lanes
 */
export function allEditRows(lanes) {
  /** @type {{lane: string, top: number, bottom: number}[]} */
  const out = [];
  for (const { lane, row } of lanes) {
    if (row.hidden || !lane.editRows) continue;
    const top = row.offsetTop;
    for (const r of lane.editRows(lane.height)) out.push({ lane: r.lane, top: top + r.y0, bottom: top + r.y1 });
  }
  return out;
}

/**
 * Shade the selected ticks on a lane: its chosen edit rows strongly, else the whole lane faintly.
 * @param {CanvasRenderingContext2D} ctx
 * @param {Lane} lane
 * @param {Selection|null} sel
 * @param {{tickToX: (tick: number) => number, width: number}} view
 */
export function drawSelection(ctx, lane, sel, view) {
  if (!sel) return;
  const x0 = view.tickToX(sel.t0);
  const x1 = view.tickToX(sel.t1);
  if (x1 < 0 || x0 > view.width) return;
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
