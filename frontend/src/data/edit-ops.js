/**
 * Edit operations as the API takes them (docs/API.md "Edit operations"), built from the
 * selection, and the clipboard. Pure functions: the editor submits what they return.
 */

import { rangesOf } from "../core/selection.js";

/** @typedef {import("../core/timeline.js").Selection} Selection */

/** Most sub-ops one `group` op takes. */
export const GROUP_MAX = 10000;

/**
 * One op per range of the selection (a selection of several shots has several), as ONE op: the
 * op itself for one range, else a `group` (one undo step).
 * @param {Selection} sel
 * @param {(range: Selection) => Record<string, any>} build
 */
export function perRange(sel, build) {
  const ops = rangesOf(sel).map(([t0, t1]) => build({ t0, t1, lanes: sel.lanes }));
  return groupOf(ops);
}

/** Ops as one: the op itself when alone, else `{"op": "group", "ops": [...]}`. @param {Array<Record<string, any>>} ops */
export function groupOf(ops) {
  if (!ops.length) throw new Error("There is nothing to change.");
  if (ops.length > GROUP_MAX) throw new Error(`One operation changes at most ${GROUP_MAX} ranges.`);
  return ops.length === 1 ? ops[0] : { op: "group", ops };
}

/**
 * `set`: one value on every selected lane. Temperature values are in C, the others 0..1, so a
 * selection mixing both cannot take one value.
 * @param {Selection} sel
 * @param {number} value
 */
export function setOp(sel, value) {
  const temp = sel.lanes.includes("temperature");
  if (temp && sel.lanes.length > 1) {
    throw new Error("Set temperature on its own: it takes °C, the other lanes take 0..1.");
  }
  if (!Number.isFinite(value)) throw new Error("Enter a number to set.");
  if (!temp && (value < 0 || value > 1)) throw new Error("Intensity values lie between 0 and 1.");
  return { op: "set", lanes: [...sel.lanes], t0: sel.t0, t1: sel.t1, value };
}

/** @param {Selection} sel @param {number} factor */
export function scaleOp(sel, factor) {
  if (!Number.isFinite(factor) || factor < 0) throw new Error("The scale factor must be a number ≥ 0.");
  return { op: "scale", lanes: [...sel.lanes], t0: sel.t0, t1: sel.t1, factor };
}

/** @param {Selection} sel */
export function clearOp(sel) {
  return { op: "clear", lanes: [...sel.lanes], t0: sel.t0, t1: sel.t1 };
}

/** @param {Selection} sel @param {"in"|"out"} kind */
export function fadeOp(sel, kind) {
  return { op: kind === "in" ? "fade_in" : "fade_out", lanes: [...sel.lanes], t0: sel.t0, t1: sel.t1 };
}

/**
 * A range op limited to a region of the fan grid (`cells`), when one is picked and the op edits the fans.
 * @param {Record<string, any>} op
 * @param {Array<[number, number]>} cells [row, col]
 */
export function inRegion(op, cells) {
  if (!cells.length || !op.lanes.includes("fans")) return op;
  if (op.lanes.length > 1) {
    throw new Error("A fan region applies to the Fans lane alone: edit only Fans, or clear the region (Escape on the fan grid).");
  }
  return { ...op, cells: cells.map(([r, c]) => [r, c]) };
}

/**
 * `temp_points` over the span of the points: temperature is piecewise linear through them.
 * @param {Array<[number, number]>} points [tick, C]
 */
export function tempPointsOp(points) {
  if (!points.length) throw new Error("Place at least one temperature point first.");
  const sorted = [...points].sort((a, b) => a[0] - b[0]);
  return {
    op: "temp_points",
    t0: sorted[0][0],
    t1: sorted[sorted.length - 1][0] + 1,
    points: sorted.map(([t, c]) => [t, c]),
  };
}

/** A marker id unique enough within one project (the API takes 1..64 characters). */
export function newMarkerId() {
  const rand = new Uint32Array(2);
  crypto.getRandomValues(rand);
  return `m${Date.now().toString(36)}${rand[0].toString(36)}${rand[1].toString(36)}`;
}

/** @param {number} t_s @param {string} label */
export function markerAddOp(t_s, label) {
  return { op: "marker_add", marker: { id: newMarkerId(), t_s, label } };
}

/** @param {string} id @param {{t_s?: number, label?: string}} change */
export function markerUpdateOp(id, change) {
  return { op: "marker_update", marker: { id, ...change } };
}

/** @param {string} id */
export function markerDeleteOp(id) {
  return { op: "marker_delete", id };
}

/**
 * What Copy took: per-lane values over a tick range, pasted as one `paste` op at another tick.
 */
export class Clipboard {
  constructor() {
    /** @type {{values: Record<string, any[]>, length: number}|null} */
    this.content = null;
  }

  /**
   * Hold values copied at full precision (GET /timeline/values: the same numbers the server composes).
   * @param {Record<string, any[]>} values per-lane values of one range
   * @param {number} length ticks
   */
  take(values, length) {
    this.content = { values, length };
    return this.content;
  }

  /**
   * @param {number} t0 tick where the copy starts
   * @param {number} [t1] with it, the copy is fitted (resampled in time) to [t0, t1)
   */
  pasteOp(t0, t1) {
    if (!this.content) throw new Error("Copy a selection first.");
    return t1 === undefined ? { op: "paste", t0, values: this.content.values } : { op: "paste", t0, t1, values: this.content.values };
  }
}
