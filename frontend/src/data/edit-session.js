/**
 * The client side of the edit history (docs/API.md "Timeline"): every op is POSTed at once with
 * the revision it was based on (autosave), undo/redo are server calls, and requests run one at a
 * time so the editor never races itself. A 409 means someone else changed the project: the edit
 * list is reloaded and the editor is told, so it can reload the timeline and say so.
 */

import { ApiError, errorText } from "./http.js";
import { Emitter } from "../core/events.js";

/**
 * @typedef {{revision: number, cursor: number, nOps: number}} HistoryState
 * @typedef {{
 *   changed: HistoryState & {reason: "edit"|"undo"|"redo"|"reload"|"conflict"|"params",
 *     params?: import("./api.js").Params|null, job?: import("./api.js").Job|null},
 *   save: {state: "saved"|"saving"|"error", message: string},
 *   conflict: {message: string},
 * }} HistoryEvents
 */

/** @extends {Emitter<HistoryEvents>} */
export class EditSession extends Emitter {
  /**
   * @param {import("./api.js").Api} api
   * @param {string} projectId
   * @param {import("./api.js").EditList} edits
   */
  constructor(api, projectId, edits) {
    super();
    this.api = api;
    this.projectId = projectId;
    this.revision = edits.revision;
    this.cursor = edits.cursor;
    /** @type {Array<Record<string, any>>} */
    this.ops = edits.ops;
    /** @type {import("./api.js").Marker[]} the markers at the cursor, as the server composes them */
    this.markers = edits.markers || [];
    this._pending = 0;
    /** @type {unknown} the failure of the latest request, null when it succeeded */
    this._lastError = null;
    /** @type {Promise<any>} */
    this._chain = Promise.resolve();
  }

  get nOps() {
    return this.ops.length;
  }

  get canUndo() {
    return this.cursor > 0;
  }

  get canRedo() {
    return this.cursor < this.ops.length;
  }

  /** @returns {HistoryState} */
  state() {
    return { revision: this.revision, cursor: this.cursor, nOps: this.ops.length };
  }

  /**
   * Append one op (drops the redo tail). Resolves true when saved, false when refused.
   * @param {Record<string, any>} op
   */
  submit(op) {
    return this.run(async () => {
      const res = await this.api.postEdit(this.projectId, this.revision, op);
      this.ops = [...this.ops.slice(0, res.cursor - 1), res.op];
      this._apply(res, "edit");
    });
  }

  /**
   * Replace every track by an imported timeline file (our JSON or CSV): one undoable `import` op.
   * @param {File} file
   */
  importFile(file) {
    return this.run(async () => {
      const res = await this.api.importFile(this.projectId, file, this.revision).promise;
      this.ops = [...this.ops.slice(0, res.cursor - 1), res.op];
      this._apply(res, "edit");
    });
  }

  undo() {
    return this.run(async () => {
      if (!this.canUndo) return;
      this._apply(await this.api.undo(this.projectId, this.revision), "undo");
    });
  }

  redo() {
    return this.run(async () => {
      if (!this.canRedo) return;
      this._apply(await this.api.redo(this.projectId, this.revision), "redo");
    });
  }

  /**
   * Run a request that changes the revision (an edit, a parameter change) after the ones before
   * it; resolves true on success, false when it failed (the failure is reported through events).
   * @param {() => Promise<void>} fn
   * @returns {Promise<boolean>}
   */
  run(fn) {
    this._pending++;
    this.emit("save", { state: "saving", message: "Saving…" });
    const next = this._chain.then(async () => {
      try {
        await fn();
        return true;
      } catch (err) {
        await this._failed(err);
        return false;
      } finally {
        this._pending--;
      }
    });
    this._chain = next.then(() => {
      if (this._pending === 0 && this._lastError === null) this.emit("save", { state: "saved", message: "All changes saved" });
    });
    this._lastError = null;
    return next;
  }

  /** Re-read the edit list (after a conflict, a regeneration, or on demand). */
  async reload() {
    this._take(await this.api.edits(this.projectId));
    this.emit("changed", { ...this.state(), reason: "reload" });
  }

  /** @param {import("./api.js").EditList} e */
  _take(e) {
    this.revision = e.revision;
    this.cursor = e.cursor;
    this.ops = e.ops;
    this.markers = e.markers || [];
  }

  /**
   * A parameter change or a finished job moved the revision; a parameter change the server
   * recorded as a `params` op (PUT params answers its `cursor`) is the newest op.
   * @param {number} revision
   * @param {number|null} [cursor]
   */
  setRevision(revision, cursor = null) {
    this.revision = revision;
    if (typeof cursor === "number") {
      this.ops = [...this.ops.slice(0, cursor - 1), { op: "params" }];
      this.cursor = cursor;
    }
    this.emit("changed", { ...this.state(), reason: "params" });
  }

  /**
   * @param {{revision: number, cursor: number, markers: import("./api.js").Marker[],
   *   params?: import("./api.js").Params|null, job?: import("./api.js").Job|null}} res
   * @param {"edit"|"undo"|"redo"} reason
   */
  _apply(res, reason) {
    this.revision = res.revision;
    this.cursor = res.cursor;
    this.markers = res.markers;
    this.emit("changed", { ...this.state(), reason, params: res.params || null, job: res.job || null });
  }

  /** @param {unknown} err */
  async _failed(err) {
    if (err instanceof ApiError && err.status === 409) {
      const message = `${err.detail} The latest edits were reloaded; your last change was not applied.`;
      try {
        this._take(await this.api.edits(this.projectId));
        this.emit("changed", { ...this.state(), reason: "conflict" });
      } catch (reloadErr) {
        this._lastError = reloadErr;
        this.emit("save", { state: "error", message: `Could not reload the edits: ${errorText(reloadErr)}` });
        return;
      }
      this.emit("conflict", { message });
      return;
    }
    this._lastError = err;
    this.emit("save", { state: "error", message: `Not saved: ${errorText(err)}` });
  }
}
