/**
 * The Export menu: one download link per format the server offers.
 */

import { h } from "../core/dom.js";

const LABELS = /** @type {Record<string, string>} */ ({
  json: "JSON (native timeline)",
  csv: "CSV (one row per tick)",
  ahap: "AHAP (Apple Core Haptics, zip)",
  hjif: "MPEG-I haptics (.hjif)",
  mpegv: "MPEG-V SEM (XML)",
});

/**
 * @param {import("../data/api.js").Api} api
 * @param {string} projectId
 * @param {Array<{name: string, description: string}>} formats
 */
export function exportMenu(api, projectId, formats) {
  const list = h("div", { class: "menu-list", role: "menu" });
  for (const { name, description } of formats) {
    list.append(
      h("a", { class: "menu-item", role: "menuitem", href: api.exportUrl(projectId, name), download: "", title: description || undefined, "data-testid": `export-${name}` },
        LABELS[name] || name.toUpperCase()),
    );
  }
  const menu = h("details", { class: "menu", "data-testid": "export-menu" }, h("summary", { class: "btn", "aria-haspopup": "menu" }, "Export"), list);
  list.addEventListener("click", () => menu.removeAttribute("open"));
  document.addEventListener("click", (e) => {
    if (menu.open && !menu.contains(/** @type {Node} */ (e.target))) menu.removeAttribute("open");
  });
  return menu;
}
