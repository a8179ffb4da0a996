/**
 * The selection: a tick range [t0, t1) on a set of edit lanes, or (selected by shots) several
 * disjoint ranges `ranges` with [t0, t1) their span. Pure helpers the timeline core uses to clamp
 * it, to find the edit rows a drag crosses, and to draw it over a lane.
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
  const lanes = [...new Set(sel.lanes)];
  if (sel.ranges && sel.ranges.length) {
    /** @type {Array<[number, number]>} */
    const ranges = [];
    const sorted = sel.ranges.map(([a, b]) => clampRange(a, b, nTicks)).sort((p, q) => p[0] - q[0]);
    for (const r of sorted) {
      const last = ranges[ranges.length - 1];
      if (last && r[0] < last[1]) last[1] = Math.max(last[1], r[1]); // overlapping: one range
      else ranges.push(r);
    }
    return { t0: ranges[0][0], t1: ranges[ranges.length - 1][1], lanes, ranges };
  }
  const [t0, t1] = clampRange(sel.t0, sel.t1, nTicks);
  return { t0, t1, lanes };
}

/** @param {number} a @param {number} b @param {number} nTicks @returns {[number, number]} */
function clampRange(a, b, nTicks) {
  const t0 = Math.max(0, Math.min(nTicks - 1, Math.floor(Math.min(a, b))));
  const t1 = Math.max(t0 + 1, Math.min(nTicks, Math.ceil(Math.max(a, b))));
  return [t0, t1];
}

/** The tick ranges a selection covers: its `ranges`, or its one range. @param {Selection} sel @returns {Array<[number, number]>} */
export function rangesOf(sel) {
  return sel.ranges && sel.ranges.length ? sel.ranges.map(([a, b]) => [a, b]) : [[sel.t0, sel.t1]];
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
  if (view.tickToX(sel.t1) < 0 || view.tickToX(sel.t0) > view.width) return;
  const rows = lane.editRows ? lane.editRows(lane.height) : [];
  const chosen = rows.filter((r) => sel.lanes.includes(r.lane));
  ctx.save();
  ctx.fillStyle = chosen.length ? "rgba(96, 165, 250, 0.22)" : "rgba(96, 165, 250, 0.07)";
  ctx.strokeStyle = "rgba(147, 197, 253, 0.9)";
  ctx.lineWidth = 1;
  for (const [t0, t1] of rangesOf(sel)) {
    const x0 = view.tickToX(t0);
    const x1 = view.tickToX(t1);
    if (x1 < 0 || x0 > view.width) continue;
    if (!chosen.length) ctx.fillRect(x0, 0, x1 - x0, lane.height);
    for (const r of chosen) {
      ctx.fillRect(x0, r.y0, x1 - x0, r.y1 - r.y0);
      ctx.strokeRect(x0 + 0.5, r.y0 + 0.5, Math.max(0, x1 - x0 - 1), r.y1 - r.y0 - 1);
    }
  }
  ctx.restore();
}
