/**
 * The Regenerate dialog: preset, mode and thresholds from /api/config, and the learned style to
 * derive in; resolves the parameters to POST to /generate, or null when cancelled.
 */

import { h } from "../core/dom.js";
import { modal, openModal } from "./widgets.js";
import { FEATURE_LABELS } from "../lanes/features.js";

const KEEP = "keep"; // the style in use, no longer stored: left out of the request, so it stays

/**
 * `styles`: the stored styles; `style`: the one in use ({id, name}) or null. A style in use that
 * is no longer stored stays selectable (its copy in the project's parameters is kept).
 * @param {{presets: string[], modes: string[], preset: string, mode: string, thresholds: Record<string, number>,
 *   styles: Array<{id: string|null, name: string}>, style: {id: string, name: string}|null}} opts
 * @returns {Promise<import("../data/api.js").Params|null>}
 */
export function regenerateDialog({ presets, modes, preset, mode, thresholds, styles, style }) {
  return new Promise((resolve) => {
    const presetSel = h("select", { class: "input", "data-testid": "regen-preset" });
    for (const p of presets) presetSel.add(new Option(p, p, false, p === preset));
    const modeSel = h("select", { class: "input", "data-testid": "regen-mode" });
    for (const m of modes) modeSel.add(new Option(m, m, false, m === mode));
    const styleSel = h("select", { class: "input", "data-testid": "regen-style" });
    styleSel.add(new Option("None", ""));
    for (const st of styles) styleSel.add(new Option(st.name, st.id || "", false, !!style && st.id === style.id));
    if (style && !styles.some((st) => st.id === style.id)) styleSel.add(new Option(`${style.name} (deleted)`, KEEP, false, true));
    /** @type {Record<string, HTMLInputElement>} */
    const inputs = {};
    const thrFields = Object.entries(thresholds).map(([name, v]) => {
      const input = h("input", { type: "number", class: "input", min: 0, max: 1, step: 0.01, value: String(v), required: true, "data-testid": `regen-threshold-${name}` });
      inputs[name] = input;
      return h("label", { class: "field" }, h("span", { class: "field-label" }, FEATURE_LABELS[name] || name), input);
    });
    const ok = h("button", { class: "btn btn-primary", value: "ok", "data-testid": "regen-start" }, "Regenerate");
    const cancel = h("button", { class: "btn", value: "cancel", formnovalidate: true }, "Cancel");
    const dlg = modal(
      "Regenerate the timeline",
      [
        h("p", { class: "dialog-message" }, "Analyses the media again with these settings. Your manual edits are kept and applied on top."),
        h("div", { class: "field-grid" },
          h("label", { class: "field" }, h("span", { class: "field-label" }, "Preset"), presetSel),
          h("label", { class: "field" }, h("span", { class: "field-label" }, "Mode"), modeSel),
          h("label", { class: "field" }, h("span", { class: "field-label" }, "Style"), styleSel)),
        h("fieldset", { class: "field-grid" }, h("legend", {}, "Thresholds"), ...thrFields),
      ],
      [cancel, ok],
    );
    dlg.setAttribute("data-testid", "regenerate-dialog");
    dlg.addEventListener("close", () => {
      if (dlg.returnValue !== "ok") resolve(null);
      else {
        /** @type {Record<string, number>} */
        const thr = {};
        for (const [name, input] of Object.entries(inputs)) thr[name] = Number(input.value);
        /** @type {import("../data/api.js").Params} */
        const params = { preset: presetSel.value, mode: modeSel.value, thresholds: thr };
        if (styleSel.value !== KEEP) params.style = styleSel.value || null;
        resolve(params);
      }
      dlg.remove();
    });
    openModal(dlg);
  });
}
