/**
 * Small shared widgets: modal dialogs (confirm / prompt) built on <dialog>, the toast area for
 * messages that need no answer, and a progress bar.
 */

import { h } from "../core/dom.js";

/**
 * A modal dialog with a message and OK / Cancel; resolves true on OK. A `danger` dialog (OK
 * destroys something) opens with the focus on Cancel, so Enter never destroys.
 * @param {{title: string, message: string, ok?: string, danger?: boolean}} opts
 * @returns {Promise<boolean>}
 */
export function confirmDialog({ title, message, ok = "OK", danger = false }) {
  return new Promise((resolve) => {
    const okBtn = h("button", { class: danger ? "btn btn-danger" : "btn btn-primary", value: "ok", "data-testid": "dialog-ok" }, ok);
    const cancelBtn = h("button", { class: "btn", value: "cancel", "data-testid": "dialog-cancel", formnovalidate: true }, "Cancel");
    const dlg = modal(title, [h("p", { class: "dialog-message" }, message)], [cancelBtn, okBtn]);
    dlg.addEventListener("close", () => {
      resolve(dlg.returnValue === "ok");
      dlg.remove();
    });
    openModal(dlg, danger ? cancelBtn : null);
  });
}

/**
 * A modal dialog asking for one line of text; resolves the trimmed text, or null when cancelled.
 * @param {{title: string, label: string, value?: string, ok?: string, maxLength?: number}} opts
 * @returns {Promise<string|null>}
 */
export function promptDialog({ title, label, value = "", ok = "OK", maxLength = 200 }) {
  return new Promise((resolve) => {
    const input = h("input", { type: "text", class: "input", value, maxlength: maxLength, required: true, "data-testid": "dialog-input" });
    const field = h("label", { class: "field" }, h("span", { class: "field-label" }, label), input);
    const okBtn = h("button", { class: "btn btn-primary", value: "ok", "data-testid": "dialog-ok" }, ok);
    const cancelBtn = h("button", { class: "btn", value: "cancel", "data-testid": "dialog-cancel", formnovalidate: true }, "Cancel");
    const dlg = modal(title, [field], [cancelBtn, okBtn]);
    dlg.addEventListener("close", () => {
      resolve(dlg.returnValue === "ok" ? input.value.trim() : null);
      dlg.remove();
    });
    openModal(dlg);
  });
}

/**
 * A <dialog> with a form (method=dialog): Enter in a field submits the primary (value "ok")
 * button, Escape and a value-"cancel" button cancel (returnValue "cancel"). The cancel buttons
 * are type=button, because implicit submission presses the form's first submit button.
 * {@link openModal} opens it with the focus in the first field.
 * @param {string} title
 * @param {Node[]} body
 * @param {HTMLButtonElement[]} buttons
 */
export function modal(title, body, buttons) {
  for (const b of buttons) {
    if (b.value !== "cancel") continue;
    b.type = "button";
    b.addEventListener("click", () => b.closest("dialog")?.close("cancel"));
  }
  const titleId = `dlg-${Math.random().toString(36).slice(2)}`;
  const form = h(
    "form",
    { method: "dialog", class: "dialog-form" },
    h("h2", { class: "dialog-title", id: titleId }, title),
    ...body,
    h("div", { class: "dialog-buttons" }, ...buttons),
  );
  const dlg = h("dialog", { class: "dialog", "aria-labelledby": titleId, "data-testid": "dialog" }, form);
  dlg.addEventListener("cancel", () => {
    dlg.returnValue = "cancel";
  });
  document.body.append(dlg);
  return dlg;
}

/**
 * Show a {@link modal} with the focus (and selection) on `start`, else in its first field, else on
 * its primary button.
 * @param {HTMLDialogElement} dlg
 * @param {HTMLElement|null} [start]
 */
export function openModal(dlg, start = null) {
  dlg.showModal();
  const first = /** @type {HTMLElement|null} */ (start || dlg.querySelector("input, select, textarea") || dlg.querySelector('button[value="ok"]'));
  if (!first) return;
  first.focus();
  if (first instanceof HTMLInputElement && (first.type === "text" || first.type === "number")) first.select();
}

/**
 * Show a short message in the toast area (role=status, so screen readers read it).
 * @param {string} text
 * @param {"info"|"error"|"warn"} [kind]
 * @param {number} [ms] how long it stays
 */
export function toast(text, kind = "info", ms = 6000) {
  let area = document.getElementById("toasts");
  if (!area) {
    area = h("div", { id: "toasts", class: "toasts", role: "status", "aria-live": "polite" });
    document.body.append(area);
  }
  const item = h("div", { class: `toast toast-${kind}`, "data-testid": `toast-${kind}` }, text);
  area.append(item);
  setTimeout(() => item.remove(), ms);
  return item;
}

/**
 * A progress bar (role=progressbar with aria-valuenow in percent).
 * @param {string} label accessible name
 * @param {string} testid
 */
export function progressBar(label, testid) {
  const fill = h("div", { class: "progress-fill" });
  const text = h("span", { class: "progress-text" }, "0 %");
  const bar = h(
    "div",
    { class: "progress", role: "progressbar", "aria-label": label, "aria-valuemin": 0, "aria-valuemax": 100, "aria-valuenow": 0, "data-testid": testid },
    fill,
    text,
  );
  return {
    el: bar,
    /** @param {number} fraction 0..1 @param {string} [note] */
    set(fraction, note = "") {
      const pct = Math.max(0, Math.min(100, Math.round(fraction * 100)));
      bar.setAttribute("aria-valuenow", String(pct));
      fill.style.width = `${pct}%`;
      text.textContent = note ? `${pct} % · ${note}` : `${pct} %`;
    },
  };
}
