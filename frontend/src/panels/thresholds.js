/**
 * Threshold sliders, the keyboard-friendly twin of the threshold lines: `input` is the live
 * preview, `change` (release, or a keyboard step) the commit.
 */

import { h } from "../core/dom.js";
import { FEATURE_LABELS } from "../lanes/features.js";

export class ThresholdsPanel {
  /**
   * @param {string[]} names
   * @param {{onInput: (name: string, value: number) => void, onCommit: (name: string, value: number) => void}} hooks
   */
  constructor(names, hooks) {
    /** @type {Map<string, {input: HTMLInputElement, out: HTMLOutputElement}>} */
    this.rows = new Map();
    const list = h("div", { class: "thresholds" });
    for (const name of names) {
      const id = `thr-${name}`;
      const input = h("input", {
        type: "range", min: 0, max: 1, step: 0.01, id, class: "range", "data-testid": `threshold-${name}`,
      });
      const out = h("output", { class: "range-value", for: id }, "–");
      input.addEventListener("input", () => {
        out.textContent = Number(input.value).toFixed(2);
        hooks.onInput(name, Number(input.value));
      });
      input.addEventListener("change", () => hooks.onCommit(name, Number(input.value)));
      list.append(h("label", { class: "threshold-row", for: id }, h("span", {}, FEATURE_LABELS[name] || name), input, out));
      this.rows.set(name, { input, out });
    }
    this.el = h("section", { class: "panel", "aria-labelledby": "thr-title" }, h("h2", { class: "panel-title", id: "thr-title" }, "Thresholds"), list);
  }

  /** @param {string} name @param {number} value */
  set(name, value) {
    const row = this.rows.get(name);
    if (!row) return;
    row.input.value = String(value);
    row.out.textContent = value.toFixed(2);
  }

  /** @param {boolean} disabled */
  setDisabled(disabled) {
    for (const { input } of this.rows.values()) input.disabled = disabled;
  }
}
