/**
 * The marker list at an edit cursor, read from the op list (GET /edits) so the editor does not
 * download the whole composed document for it: marker_add / marker_update / marker_delete in
 * order, the way the server composes them (docs/API.md "Edit operations"; times past the end
 * are held at the end).
 */

/**
 * @param {Array<Record<string, any>>} ops
 * @param {number} cursor ops[0:cursor] are applied
 * @param {number} durationS
 * @returns {Array<{id: string, t_s: number, label: string}>} sorted by time, then id
 */
export function foldMarkers(ops, cursor, durationS) {
  /** @type {Map<string, {id: string, t_s: number, label: string}>} */
  const markers = new Map();
  for (const op of ops.slice(0, cursor)) {
    if (op.op === "marker_add" && op.marker) {
      markers.set(op.marker.id, { id: op.marker.id, t_s: Math.min(op.marker.t_s, durationS), label: op.marker.label ?? "" });
    } else if (op.op === "marker_update" && op.marker && markers.has(op.marker.id)) {
      const m = /** @type {{id: string, t_s: number, label: string}} */ (markers.get(op.marker.id));
      if (typeof op.marker.t_s === "number") m.t_s = Math.min(op.marker.t_s, durationS);
      if (typeof op.marker.label === "string") m.label = op.marker.label;
    } else if (op.op === "marker_delete") {
      markers.delete(op.id);
    }
  }
  return [...markers.values()].sort((a, b) => a.t_s - b.t_s || (a.id < b.id ? -1 : a.id > b.id ? 1 : 0));
}
