/**
 * Threshold sliders, the keyboard-friendly twin of the threshold lines: `input` is the live
 * preview, `change` (release, or a keyboard step) the commit; beside each a field to type the value. Beside them the density control
 * (the share of the film that should vibrate: off = the thresholds as they are, on = the server
 * scales the thresholds so about that share vibrates) and the share the current settings give.
 */

import { h } from "../core/dom.js";
import { FEATURE_LABELS } from "../lanes/features.js";
import { toast } from "./widgets.js";

/** @param {number} share 0..1 @returns {string} */
const percent = (share) => `${Math.round(share * 100)} %`;

export class ThresholdsPanel {
  /**
   * @param {string[]} names
   * @param {{onInput: (name: string, value: number) => void, onCommit: (name: string, value: number) => void,
   *   onDensity?: (share: number|null) => void}} hooks
   */
  constructor(names, hooks) {
    /** @type {Map<string, {input: HTMLInputElement, out: HTMLInputElement, value: number}>} the slider, the typed value, the value shown */
    this.rows = new Map();
    const list = h("div", { class: "thresholds" });
    for (const name of names) {
      const id = `thr-${name}`;
      const input = h("input", {
        type: "range", min: 0, max: 1, step: 0.01, id, class: "range", "data-testid": `threshold-${name}`,
      });
      const label = FEATURE_LABELS[name] || name;
      const out = h("input", { type: "number", min: 0, max: 1, step: 0.001, class: "input range-value",
        "aria-label": `${label} threshold (0 to 1)`, "data-testid": `threshold-value-${name}` });
      input.addEventListener("input", () => {
        out.value = Number(input.value).toFixed(2);
        hooks.onInput(name, Number(input.value));
      });
      input.addEventListener("change", () => hooks.onCommit(name, Number(input.value)));
      out.addEventListener("change", () => this._typed(name, out, hooks.onCommit));
      list.append(h("label", { class: "threshold-row", for: id }, h("span", {}, label), input, out));
      this.rows.set(name, { input, out, value: 0 });
    }
    const density = this._densityRow(hooks.onDensity || (() => {}));
    this.share = h("p", { class: "params-info", "data-testid": "vibration-share", "aria-live": "polite" }, "");
    this.el = h("section", { class: "panel", "aria-labelledby": "thr-title" },
      h("h2", { class: "panel-title", id: "thr-title" }, "Thresholds"), list, density, this.share);
  }

  /** The density row: a checkbox that turns it on and a slider for the share. @param {(share: number|null) => void} onDensity */
  _densityRow(onDensity) {
    this.densityOn = h("input", { type: "checkbox", id: "density-on", "data-testid": "density-on",
      "aria-label": "Set the share of the film that vibrates" });
    this.density = h("input", { type: "range", min: 0, max: 1, step: 0.01, value: 0.25, id: "density", class: "range",
      "data-testid": "density", disabled: true });
    this.densityOut = h("output", { class: "range-value", for: "density" }, "off");
    const commit = () => onDensity(this.densityOn.checked ? Number(this.density.value) : null);
    this.densityOn.addEventListener("change", () => {
      this.density.disabled = !this.densityOn.checked;
      this._showDensity();
      commit();
    });
    this.density.addEventListener("input", () => this._showDensity());
    this.density.addEventListener("change", commit);
    return h("label", { class: "threshold-row", for: "density",
      title: "Share of the film that vibrates: the thresholds are scaled together to give about this share" },
    h("span", {}, this.densityOn, " Density"), this.density, this.densityOut);
  }

  _showDensity() {
    this.densityOut.textContent = this.densityOn.checked ? percent(Number(this.density.value)) : "off";
  }

  /**
   * A typed threshold: a number 0..1 is committed as typed (to 0.001); anything else is refused
   * with a warning and the field shows the value in force again.
   * @param {string} name @param {HTMLInputElement} out @param {(name: string, value: number) => void} onCommit
   */
  _typed(name, out, onCommit) {
    const row = this.rows.get(name);
    const v = out.value.trim() === "" ? NaN : Number(out.value);
    if (!Number.isFinite(v) || v < 0 || v > 1) {
      toast(`A threshold is a number from 0 to 1; "${out.value}" was not used.`, "warn");
      this.set(name, row.value);
      return;
    }
    onCommit(name, Math.round(v * 1000) / 1000);
  }

  /** @param {string} name @param {number} value */
  set(name, value) {
    const row = this.rows.get(name);
    if (!row) return;
    row.value = value;
    row.input.value = String(value);
    row.out.value = String(Math.round(value * 1000) / 1000);
  }

  /** The density setting: a share 0..1, or null (off). @param {number|null} share */
  setDensity(share) {
    this.densityOn.checked = share !== null;
    this.density.disabled = share === null || this.densityOn.disabled;
    if (share !== null) this.density.value = String(share);
    this._showDensity();
  }

  /** The share of the film's ticks the current settings make vibrate (null: no timeline). @param {number|null} share */
  setShare(share) {
    this.share.textContent = share === null ? "" : `Vibrates on ${percent(share)} of the film`;
  }

  /** @param {boolean} disabled */
  setDisabled(disabled) {
    for (const { input, out } of this.rows.values()) input.disabled = out.disabled = disabled;
    this.densityOn.disabled = disabled;
    this.density.disabled = disabled || !this.densityOn.checked;
  }
}
