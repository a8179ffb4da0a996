/**
 * Editing in the editor: the toolbar and its tool, the operations on the selection, pencil
 * strokes, temperature points, copy and paste, import, undo and redo. Every change is one op saved
 * through the edit session (autosave); the composed timeline is reloaded when the server took it.
 */

import { rangesOf } from "../../core/selection.js";
import { Clipboard, clearOp, fadeOp, groupOf, inRegion, perRange, scaleOp, setOp, tempPointsOp } from "../../data/edit-ops.js";
import { errorText } from "../../data/http.js";
import { EditToolbar } from "../../panels/toolbar.js";
import { toast } from "../../panels/widgets.js";

/** @typedef {import("../../core/timeline.js").Selection} Selection */

export class EditActions {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    this.clipboard = new Clipboard();
    /** @type {Array<[number, number]>} temperature points placed, not applied yet: [tick, C] */
    this.points = [];
    /** @type {EditToolbar|null} */
    this.toolbar = null;
    /** @type {Array<[number, number]>} fans picked on the fan grid: range ops on Fans change only these */
    this.region = [];
  }

  /** The fan grid's picked region changed. @param {Array<[number, number]>} cells */
  takeRegion(cells) {
    this.region = cells;
    this.updateToolbar();
  }

  buildToolbar() {
    const markers = this.page.markers;
    this.toolbar = new EditToolbar({
      tool: (t) => this.setTool(t),
      toggleLane: (lane) => this.toggleLane(lane),
      set: (v) => this.selectionOp((sel) => setOp(sel, v)),
      scale: (f) => this.selectionOp((sel) => scaleOp(sel, f)),
      clear: () => this.selectionOp((sel) => clearOp(sel)),
      fade: (k) => this.selectionOp((sel) => fadeOp(sel, k)),
      copy: () => this.copy(),
      paste: () => this.paste(),
      applyPoints: () => this.applyPoints(),
      discardPoints: () => this.setPoints([]),
      addMarker: () => markers.add(this.page.media.player.currentTime),
      renameMarker: () => markers.selected && markers.rename(markers.selected),
      deleteMarker: () => markers.selected && markers.remove(markers.selected),
      splitShot: () => this.page.shots.split(),
      mergeShot: () => this.page.shots.merge(),
    }, this.page.layout.editLanes);
    return this.toolbar.el;
  }

  updateToolbar() {
    const page = this.page;
    const tl = page.timeline;
    if (!tl) return;
    const sel = tl.selection;
    this.toolbar.update({
      tool: tl.tool,
      selection: sel,
      lanes: sel ? sel.lanes : tl.defaultLanes,
      tickS: page.tickS,
      canPaste: !!this.clipboard.content,
      points: this.points.length,
      markerSelected: !!page.markers.selected,
      ready: !!page.data,
      cells: this.region.length,
      shots: !!page.shots.list && page.shots.list.length > 0,
    });
  }

  /** @param {"select"|"pencil"|"points"} tool */
  setTool(tool) {
    this.page.timeline.tool = tool;
    if (tool !== "points" && this.points.length) this.setPoints([]);
    this.updateToolbar();
  }

  /** Add a lane to the edit lanes, or take it out. @param {string} lane */
  toggleLane(lane) {
    const tl = this.page.timeline;
    const sel = tl.selection;
    const current = sel ? sel.lanes : tl.defaultLanes;
    const next = current.includes(lane) ? current.filter((l) => l !== lane) : [...current, lane];
    if (!next.length) return;
    if (sel) tl.setSelection({ ...sel, lanes: next });
    else tl.defaultLanes = next;
    this.updateToolbar();
  }

  /**
   * One op on the selection: on each of its ranges when it has several (shots), as one `group`.
   * @param {(sel: Selection) => Record<string, any>} build
   */
  selectionOp(build) {
    const sel = this.page.timeline.selection;
    if (!sel) {
      toast("Select a range first (drag on the lanes).", "warn");
      return Promise.resolve(false);
    }
    let op;
    try {
      op = perRange(sel, (range) => inRegion(build(range), this.region));
    } catch (err) {
      toast(errorText(err), "warn");
      return Promise.resolve(false);
    }
    return this.submit(op);
  }

  /**
   * Save one op (autosave); the composed timeline is reloaded when the server accepted it.
   * @param {Record<string, any>} op
   */
  submit(op) {
    const page = this.page;
    if (!page.session || !page.data) {
      toast("There is no timeline to edit yet.", "warn");
      return Promise.resolve(false);
    }
    return page.session.submit(op);
  }

  /**
   * @param {Record<string, any>} op
   * @param {{clearStroke: () => void}} lane
   */
  async submitStroke(op, lane) {
    const ok = await this.submit(op);
    if (!ok) {
      lane.clearStroke();
      this.page.timeline.invalidate();
    }
  }

  /** @param {File} file */
  async importTimeline(file) {
    const page = this.page;
    if (!page.session || !page.data) {
      toast("Generate a timeline before importing one over it.", "warn");
      return;
    }
    if (await page.session.importFile(file)) toast(`Imported ${file.name}; Undo brings the previous tracks back.`);
  }

  async undo() {
    if (this.page.session) await this.page.session.undo();
  }

  async redo() {
    if (this.page.session) await this.page.session.redo();
  }

  /** Copy the selection's values at full precision (from the server; the lanes hold 1/255 steps). */
  async copy() {
    const { timeline, data, api, projectId } = this.page;
    const sel = timeline.selection;
    if (!sel || !data) return;
    const n = rangesOf(sel).length;
    if (n > 1) {
      toast(`Copy takes one shot or range, and ${n} shots are selected: click the one shot to copy, then Copy.`, "warn");
      return;
    }
    const t1 = Math.min(sel.t1, data.nTicks);
    let c;
    try {
      const got = await api.laneValues(projectId, sel.lanes, sel.t0, t1);
      c = this.clipboard.take(got.values, t1 - sel.t0);
    } catch (err) {
      toast(`Could not copy: ${errorText(err)}`, "warn");
      return;
    }
    toast(`Copied ${c.length} ticks of ${sel.lanes.join(", ")}.`);
    this.updateToolbar();
  }

  /** Paste at the playhead; onto selected shots, fitted to each shot's length (one op). */
  paste() {
    const { data, media, timeline } = this.page;
    if (!this.clipboard.content) return Promise.resolve(false);
    if (!data) return Promise.resolve(false);
    const sel = timeline.selection;
    if (sel && sel.ranges) {
      const ranges = rangesOf(sel);
      return this.submit(groupOf(ranges.map(([t0, t1]) => this.clipboard.pasteOp(t0, t1))));
    }
    return this.submit(this.clipboard.pasteOp(data.tickAt(media.player.currentTime)));
  }

  /** The temperature lane's points changed. @param {Array<[number, number]>} points */
  takePoints(points) {
    this.points = points.map(([t, c]) => [t, c]);
    this.updateToolbar();
  }

  /** @param {Array<[number, number]>} points */
  setPoints(points) {
    this.points = points;
    this.page.lanes.temperature.setPoints(points);
    this.page.timeline.invalidate("temperature");
    this.updateToolbar();
  }

  async applyPoints() {
    let op;
    try {
      op = tempPointsOp(this.points);
    } catch (err) {
      toast(errorText(err), "warn");
      return;
    }
    if (await this.submit(op)) this.setPoints([]);
  }
}
