/** The element builder every view uses (no framework, no templates). */

/**
 * Create an element: h("button", {class: "btn", onclick: fn, "data-testid": "x"}, "Label").
 * Keys starting with "on" attach listeners; `class`, `text`, `hidden`, `disabled` are handled;
 * anything else becomes an attribute.
 * @template {keyof HTMLElementTagNameMap} K
 * @param {K} tag
 * @param {Record<string, any>} [attrs]
 * @param {...(Node|string|null|undefined|false)} children
 * @returns {HTMLElementTagNameMap[K]}
 */
export function h(tag, attrs = {}, ...children) {
  const el = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k.startsWith("on") && typeof v === "function") el.addEventListener(k.slice(2), v);
    else if (k === "class") el.className = v;
    else if (k === "text") el.textContent = v;
    else if (k === "hidden") el.hidden = !!v;
    else if (k === "disabled") /** @type {any} */ (el).disabled = !!v;
    else if (k === "value") /** @type {any} */ (el).value = v;
    else el.setAttribute(k, v === true ? "" : String(v));
  }
  for (const c of children) {
    if (c === null || c === undefined || c === false) continue;
    el.append(c);
  }
  return el;
}
