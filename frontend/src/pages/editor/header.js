/**
 * The editor's top bar: the project's name, the learned style in use and the save state, the chair
 * indicator and STOP, undo / redo, regenerate, Learn style, import and export.
 */

import { h } from "../../core/dom.js";
import { exportMenu } from "../../panels/export-menu.js";
import { learnStyleDialog } from "../../panels/learn-style.js";
import { toast } from "../../panels/widgets.js";

const CHAIR_TEXT = /** @type {Record<string, string>} */ ({ connected: "Chair on", reconnecting: "Chair reconnecting…" });

export class EditorHeader {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
  }

  /** Fill the page's host with the bar and an empty <main> below it; returns the <main>. */
  build() {
    const page = this.page;
    this.nameEl = h("h1", { class: "project-name", "data-testid": "project-name" }, "…");
    this.styleEl = h("span", { class: "badge style-badge", "data-testid": "style-badge", title: "The learned style the generated layer derives in (Regenerate… changes it)" }, "No style");
    this.saveEl = h("span", { class: "save-state", role: "status", "aria-live": "polite", "data-testid": "save-state" }, "");
    this.undoBtn = h("button", { class: "btn", type: "button", disabled: true, title: "Undo (Ctrl+Z)", "data-testid": "undo", onclick: () => page.edits.undo() }, "Undo");
    this.redoBtn = h("button", { class: "btn", type: "button", disabled: true, title: "Redo (Ctrl+Shift+Z)", "data-testid": "redo", onclick: () => page.edits.redo() }, "Redo");
    this.regenBtn = h("button", { class: "btn", type: "button", "data-testid": "regenerate", onclick: () => page.params.regenerate() }, "Regenerate…");
    const learnBtn = h("button", { class: "btn", type: "button", "data-testid": "learn-style", title: "Learn a reusable style from this film's edits", onclick: () => this.learnStyle() }, "Learn style…");
    const importInput = h("input", { type: "file", accept: ".json,.csv,application/json,text/csv", class: "visually-hidden", "data-testid": "import-input", "aria-hidden": "true", tabindex: -1 });  // the Import… button is the control
    importInput.addEventListener("change", () => {
      const f = importInput.files && importInput.files[0];
      importInput.value = "";
      if (f) page.edits.importTimeline(f);
    });
    const importBtn = h("button", { class: "btn", type: "button", "data-testid": "import", title: "Replace the tracks by a timeline file (JSON or CSV); undoable", onclick: () => importInput.click() }, "Import…");
    const exportSlot = h("div", { class: "export-slot" });
    this.chairIndicator = h("span", { class: "badge chair-indicator", "data-state": "idle", "data-testid": "chair-indicator", title: "Chair connection" }, "Chair off");
    const stopBtn = h(
      "button",
      { class: "btn btn-danger btn-stop", type: "button", "data-testid": "chair-stop", "aria-keyshortcuts": "Escape", title: "Stop the chair: every output off now (Escape)", onclick: () => page.chair.stop() },
      "■ Stop chair",
    );
    const header = h(
      "header",
      { class: "topbar" },
      h("a", { class: "btn btn-ghost", href: "#/", "data-testid": "back" }, "← Projects"),
      this.nameEl,
      this.styleEl,
      this.saveEl,
      h("div", { class: "spacer" }),
      this.chairIndicator,
      stopBtn,
      this.undoBtn,
      this.redoBtn,
      this.regenBtn,
      learnBtn,
      importBtn,
      importInput,
      exportSlot,
    );
    const main = h("main", { class: "editor", "data-testid": "editor" });
    page.host.replaceChildren(header, main);
    exportSlot.append(exportMenu(page.api, page.projectId, exportFormats(page.config)));
    return main;
  }

  /** The style in use ({id, name}) or null. @param {{id: string, name: string}|null} style */
  showStyle(style) {
    this.styleEl.textContent = style ? `Style: ${style.name}` : "No style";
    this.styleEl.dataset.style = style ? style.id : "";
  }

  /** Learn a style from this project's edits (the dialog shows the report before saving). */
  async learnStyle() {
    const page = this.page;
    const style = await learnStyleDialog(page.api, { id: page.projectId, name: page.project ? page.project.name : "" });
    if (style) toast(`Saved the style “${style.name}”: choose it in Upload or Regenerate.`);
  }

  /** @param {"saved"|"saving"|"error"} state @param {string} message */
  showSave(state, message) {
    this.saveEl.textContent = message;
    this.saveEl.dataset.state = state;
  }

  /** Undo / redo follow the session; the host carries its revision and cursor for tests. */
  updateHistory() {
    const s = this.page.session;
    this.undoBtn.disabled = !s || !s.canUndo;
    this.redoBtn.disabled = !s || !s.canRedo;
    if (s) {
      this.page.host.dataset.revision = String(s.revision);
      this.page.host.dataset.cursor = String(s.cursor);
    }
  }

  /** @param {string} state the chair link's state */
  showChair(state) {
    this.chairIndicator.dataset.state = state;
    this.chairIndicator.textContent = CHAIR_TEXT[state] || "Chair off";
  }
}

/**
 * The formats /api/config lists ({name, description}), else JSON and CSV.
 * @param {Record<string, any>} config
 */
function exportFormats(config) {
  const listed = config.export_formats;
  if (Array.isArray(listed) && listed.length) {
    return listed
      .map((f) => (typeof f === "string" ? { name: f, description: "" } : { name: String(f.name || ""), description: String(f.description || "") }))
      .filter((f) => f.name);
  }
  return [{ name: "json", description: "" }, { name: "csv", description: "" }];
}
