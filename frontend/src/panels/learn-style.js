/**
 * The Learn style dialog: name a style, learn it from a project's edits (a dry run: the report of
 * how much of the film's edits it explains, nothing stored), then save it. Resolves the stored
 * style, or null when cancelled.
 */

import { h } from "../core/dom.js";
import { errorText } from "../data/http.js";
import { modal, openModal } from "./widgets.js";

const METRICS = /** @type {Array<[string, string, number]>} */ ([
  ["vibration_mae", "Vibration error", 3],
  ["onset_f1", "Onset F1", 3],
  ["temperature_mae_c", "Temperature error (C)", 2],
  ["fan_mae", "Fan error", 3],
]);

/**
 * @param {import("../data/api.js").Api} api
 * @param {{id: string, name: string}} project
 * @returns {Promise<import("../data/api.js").StyleInfo|null>}
 */
export function learnStyleDialog(api, project) {
  return new Promise((resolve) => {
    const input = h("input", { type: "text", class: "input", value: `${project.name} style`, maxlength: 200, required: true, "data-testid": "style-name" });
    const report = h("div", { class: "style-report", role: "status", "aria-live": "polite", "data-testid": "style-report" },
      h("p", { class: "dialog-message" }, "Learn shows how much of this film's edits the style explains; nothing is saved until you press Save."));
    const learn = h("button", { class: "btn", type: "button", "data-testid": "style-learn" }, "Learn");
    const save = h("button", { class: "btn btn-primary", value: "ok", disabled: true, "data-testid": "style-save" }, "Save style");
    const cancel = h("button", { class: "btn", value: "cancel", formnovalidate: true }, "Cancel");
    const dlg = modal(`Learn a style from “${project.name}”`,
      [h("label", { class: "field" }, h("span", { class: "field-label" }, "Style name"), input), learn, report], [cancel, save]);
    dlg.setAttribute("data-testid", "learn-style-dialog");
    /** @type {import("../data/api.js").StyleInfo|null} */
    let stored = null;
    const busy = (/** @type {boolean} */ on) => {
      learn.disabled = on;
      save.disabled = on || !report.dataset.learned;
    };
    learn.addEventListener("click", async () => {
      busy(true);
      report.replaceChildren(h("p", { class: "dialog-message" }, "Learning…"));
      try {
        const res = await api.learnStyle(input.value.trim(), [project.id], true);
        report.replaceChildren(...reportView(res));
        report.dataset.learned = "true";
      } catch (err) {
        report.replaceChildren(h("p", { class: "dialog-message error", "data-testid": "style-error" }, errorText(err)));
        delete report.dataset.learned;
      }
      busy(false);
    });
    input.addEventListener("input", () => {
      delete report.dataset.learned;
      save.disabled = true;
    });
    save.addEventListener("click", async (e) => {
      e.preventDefault();
      busy(true);
      try {
        stored = await api.learnStyle(input.value.trim(), [project.id], false);
        dlg.close("ok");
      } catch (err) {
        report.replaceChildren(h("p", { class: "dialog-message error", "data-testid": "style-error" }, errorText(err)));
        busy(false);
      }
    });
    dlg.addEventListener("close", () => {
      resolve(dlg.returnValue === "ok" ? stored : null);
      dlg.remove();
    });
    openModal(dlg);
  });
}

/**
 * The report of a learned style: per film the share of its edits explained and the metrics of
 * the preset's and the style's timeline against the edited one; then the style's main numbers.
 * @param {import("../data/api.js").StyleInfo & {document: Record<string, any>}} res
 */
function reportView(res) {
  const rows = [];
  for (const film of res.report) {
    const share = film.explained === null ? "no edits to explain" : `explains ${Math.round(film.explained * 100)} % of the edits`;
    rows.push(h("p", { class: "dialog-message", "data-testid": "style-explained", "data-explained": String(film.explained) }, `${film.name}: ${share}`));
    const table = h("table", { class: "style-table" },
      h("thead", {}, h("tr", {}, h("th", {}, ""), h("th", {}, "Preset"), h("th", {}, "Style"))));
    const body = h("tbody", {});
    for (const [key, label, digits] of METRICS) {
      const cell = (/** @type {number|null|undefined} */ v) => h("td", {}, v === null || v === undefined ? "–" : v.toFixed(digits));
      body.append(h("tr", {}, h("th", {}, label), cell(film.plain[key]), cell(film.styled[key])));
    }
    table.append(body);
    rows.push(table);
  }
  const doc = res.document || {};
  const temp = doc.temperature || {};
  rows.push(h("p", { class: "dialog-message", "data-testid": "style-summary" },
    `Threshold scale ${Number(doc.threshold_scale ?? 1).toFixed(2)} · temperature x${Number(temp.scale ?? 1).toFixed(2)}, ` +
    `${Number(temp.offset_c ?? 0) >= 0 ? "+" : ""}${Number(temp.offset_c ?? 0).toFixed(1)} C · full vibration becomes ` +
    `${Math.round(100 * fullLevel(doc))} %`));
  return rows;
}

/** The mean over the actuators of the level full vibration (input 1) becomes. @param {Record<string, any>} doc */
function fullLevel(doc) {
  const curves = Object.values(doc.vibration || {});
  if (!curves.length) return 1;
  return curves.reduce((sum, c) => sum + Number(c[c.length - 1]), 0) / curves.length;
}
