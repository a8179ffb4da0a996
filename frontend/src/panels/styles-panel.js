/**
 * The learned styles on the projects screen: each with what it was learned from and how much of
 * those films' edits it explains, Download (the style file) and Delete; Import a style file.
 * `onChange` runs after a style was imported or deleted.
 */

import { h } from "../core/dom.js";
import { errorText } from "../data/http.js";
import { confirmDialog, toast } from "./widgets.js";

export class StylesPanel {
  /**
   * @param {import("../data/api.js").Api} api
   * @param {() => Promise<void>} onChange
   */
  constructor(api, onChange) {
    this.api = api;
    this.onChange = onChange;
    this.listEl = h("ul", { class: "project-list", "data-testid": "style-list", "aria-label": "Styles" });
    this.emptyEl = h("p", { class: "empty", "data-testid": "no-styles" }, "No styles yet: Learn style… on a project you edited, or import a style file.");
    const input = h("input", { type: "file", accept: ".json,application/json", class: "visually-hidden", "data-testid": "style-import-input", "aria-hidden": "true", tabindex: -1 });
    input.addEventListener("change", () => {
      const f = input.files && input.files[0];
      input.value = "";
      if (f) this.importFile(f);
    });
    const importBtn = h("button", { class: "btn btn-small", type: "button", "data-testid": "style-import", onclick: () => input.click() }, "Import style…");
    this.el = h("section", { class: "panel", "aria-label": "Styles" },
      h("h2", { class: "panel-title" }, "Styles"), this.listEl, this.emptyEl, h("div", { class: "project-actions" }, importBtn, input));
  }

  /** Show these styles. @param {import("../data/api.js").StyleInfo[]} styles */
  show(styles) {
    this.listEl.replaceChildren(...styles.map((st) => this._row(st)));
    this.emptyEl.hidden = styles.length > 0;
  }

  /** @param {import("../data/api.js").StyleInfo} st */
  _row(st) {
    const id = st.id || "";
    const download = h("a", { class: "btn btn-small", href: this.api.styleDownloadUrl(id), download: `${st.name}.style.json`, "data-testid": "style-download", "aria-label": `Download ${st.name}` }, "Download");
    const remove = h("button", { class: "btn btn-small", type: "button", "data-testid": "style-delete", "aria-label": `Delete ${st.name}`, onclick: () => this.remove(st) }, "Delete");
    return h("li", { class: "project-row", "data-testid": "style-row", "data-id": id },
      h("div", { class: "project-main" }, h("span", { class: "project-name-link" }, st.name), h("span", { class: "project-meta" }, describe(st))),
      h("div", { class: "project-actions" }, download, remove));
  }

  /** @param {File} file */
  async importFile(file) {
    try {
      const st = await this.api.importStyle(file).promise;
      toast(`Imported the style “${st.name}”.`);
    } catch (err) {
      toast(`Could not import ${file.name}: ${errorText(err)}`, "error");
      return;
    }
    await this.onChange();
  }

  /** @param {import("../data/api.js").StyleInfo} st */
  async remove(st) {
    const ok = await confirmDialog({
      title: "Delete the style?",
      message: `“${st.name}” leaves the list; projects made in it keep it.`,
      ok: "Delete",
      danger: true,
    });
    if (!ok || !st.id) return;
    try {
      await this.api.deleteStyle(st.id);
    } catch (err) {
      toast(`Could not delete: ${errorText(err)}`, "error");
    }
    await this.onChange();
  }
}

/** What a style was learned from and how much of each film's edits it explains. @param {import("../data/api.js").StyleInfo} st */
function describe(st) {
  if (!st.report.length) return "imported";
  const films = st.report.map((f) => (f.explained === null ? `${f.name} (no edits)` : `${f.name} (explains ${Math.round(f.explained * 100)} %)`));
  return `learned from ${films.join(", ")}`;
}
