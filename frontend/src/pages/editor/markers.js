/**
 * Markers in the editor: the list at the session's cursor, the selected one, and adding, moving,
 * renaming and deleting them (each one undoable op).
 */

import { markerAddOp, markerDeleteOp, markerUpdateOp } from "../../data/edit-ops.js";
import { formatTime } from "../../data/format.js";
import { promptDialog } from "../../panels/widgets.js";

export class MarkerActions {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {Array<{id: string, t_s: number, label: string}>} */
    this.list = [];
    /** @type {string|null} */
    this.selected = null;
  }

  /** Take the session's markers (after every change of the edit history). */
  refresh() {
    const page = this.page;
    if (!page.session) return;
    this.list = page.session.markers.map((m) => ({ ...m }));
    if (this.selected && !this.list.some((m) => m.id === this.selected)) this.selected = null;
    page.lanes.markers.settle();
    page.timeline.invalidate("markers");
    page.edits.updateToolbar();
    page.laneText.refresh();
  }

  /** @param {string|null} id */
  select(id) {
    this.selected = id;
    this.page.timeline.invalidate("markers");
    this.page.edits.updateToolbar();
  }

  /** @param {number} timeS */
  async add(timeS) {
    const label = await promptDialog({ title: "Add a marker", label: `Label at ${formatTime(timeS)}`, value: `Marker ${this.list.length + 1}`, ok: "Add" });
    if (label === null) return;
    const op = markerAddOp(Math.round(timeS * 1000) / 1000, label);
    if (await this.page.edits.submit(op)) this.select(op.marker.id);
  }

  /** @param {string} id @param {number} t_s */
  async move(id, t_s) {
    const ok = await this.page.edits.submit(markerUpdateOp(id, { t_s }));
    if (!ok) {
      this.page.lanes.markers.settle();
      this.page.timeline.invalidate("markers");
    }
  }

  /** @param {string} id */
  async rename(id) {
    const m = this.list.find((x) => x.id === id);
    if (!m) return;
    const label = await promptDialog({ title: "Rename the marker", label: "Label", value: m.label, ok: "Rename" });
    if (label === null || label === m.label) return;
    await this.page.edits.submit(markerUpdateOp(id, { label }));
  }

  /** @param {string} id */
  async remove(id) {
    const m = this.list.find((x) => x.id === id);
    if (!m) return;
    if (await this.page.edits.submit(markerDeleteOp(id))) this.select(null);
  }
}
