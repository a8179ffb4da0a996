/**
 * The Shots panel: every shot with its poster and summary, ordered and filtered (loudest, most
 * fans, warmest...), click to jump there and select it (Shift: add it), and the "shots like this"
 * slider that shows how many shots it would pick before anything changes. The list draws only
 * the rows in view (a 2-hour film has about 2,000 shots), so posters load as they scroll in.
 */

import { h } from "../core/dom.js";
import { formatTime } from "../data/format.js";
import { SHOT_FILTERS, SHOT_SORTS, arrangeShots } from "../data/shot-list.js";

const ROW_PX = 46;
const OVERSCAN = 4;

/**
 * What the panel reads and calls (pages/editor/shots.js ShotActions).
 * @typedef {{
 *   list: import("../data/shot-list.js").ShotList|null,
 *   status: string,
 *   similar: {shot: import("../data/shot-list.js").Shot, maxDistance: number, ids: Set<number>}|null,
 *   page: {tickS: number, timeline: import("../core/timeline.js").TimelineView|null, view: {scheduleSave: () => void}},
 *   jump: (shot: import("../data/shot-list.js").Shot, add: boolean) => void,
 *   selectedShot: () => import("../data/shot-list.js").Shot|null,
 *   openSimilar: (shot: import("../data/shot-list.js").Shot) => void,
 *   previewSimilar: (maxDistance: number) => void,
 *   applySimilar: () => void,
 *   closeSimilar: () => void,
 * }} ShotsPanelActions
 */

export class ShotsPanel {
  /** @param {ShotsPanelActions} actions */
  constructor(actions) {
    this.actions = actions;
    this.open = false;
    this.sort = "time";
    this.filter = "all";
    /** @type {{key: string, shots: import("../data/shot-list.js").Shot[]}|null} */
    this._arranged = null;
    /** @type {((open: boolean) => void)|null} the editor shows or hides the column */
    this.onToggle = null;
  }

  build() {
    const option = (/** @type {{id: string, label: string}} */ o) => h("option", { value: o.id }, o.label);
    this.sortEl = h("select", { class: "input shots-select", "aria-label": "Order of the shots", "data-testid": "shots-sort",
      onchange: () => { this.sort = this.sortEl.value; this.refresh(true); } }, ...SHOT_SORTS.map(option));
    this.filterEl = h("select", { class: "input shots-select", "aria-label": "Which shots to list", "data-testid": "shots-filter",
      onchange: () => { this.filter = this.filterEl.value; this.refresh(true); } }, ...SHOT_FILTERS.map(option));
    this.countEl = h("span", { class: "shots-count", "data-testid": "shots-count" });
    this.likeBtn = h("button", { class: "btn btn-small", type: "button", "data-testid": "shots-similar-open",
      title: "Select one shot first (click it on the Shots lane)", onclick: () => {
        const s = this.actions.selectedShot();
        if (s) this.actions.openSimilar(s);
      } }, "Shots like this…");
    this.slider = h("input", { type: "range", min: 0, max: 100, step: 1, value: 80, class: "shots-slider",
      "aria-label": "Similarity: the shots at least this similar are picked", "data-testid": "shots-similar-slider",
      oninput: () => this.actions.previewSimilar(1 - this.slider.valueAsNumber / 100) });
    this.similarText = h("span", { class: "shots-similar-text", "data-testid": "shots-similar-count", "aria-live": "polite" });
    this.similarBox = h("div", { class: "shots-similar", hidden: true, "data-testid": "shots-similar" },
      h("div", { class: "shots-similar-title", "data-testid": "shots-similar-title" }),
      h("label", { class: "shots-similar-row" }, "Similarity", this.slider),
      h("div", { class: "shots-similar-row" }, this.similarText,
        h("button", { class: "btn btn-small btn-primary", type: "button", "data-testid": "shots-similar-apply", onclick: () => this.actions.applySimilar() }, "Select them"),
        h("button", { class: "btn btn-small", type: "button", "data-testid": "shots-similar-cancel", onclick: () => this.actions.closeSimilar() }, "Cancel")));
    this.spacer = h("div", { class: "shots-spacer" });
    this.rowsEl = h("div", { class: "shots-rows" });
    this.listEl = h("div", { class: "shots-list", tabindex: "0", role: "list", "aria-label": "Shots", "data-testid": "shots-list" }, this.spacer, this.rowsEl);
    this.listEl.addEventListener("scroll", () => this._renderRows());
    this.listEl.addEventListener("click", (e) => {
      const row = /** @type {HTMLElement|null} */ (/** @type {HTMLElement} */ (e.target).closest(".shot-row"));
      const list = this.actions.list;
      const shot = row && list ? list.get(Number(row.dataset.id)) : null;
      if (shot) this.actions.jump(shot, e.shiftKey);
    });
    this.el = h("section", { class: "panel shots-panel", hidden: true, "aria-label": "Shots", "data-testid": "shots-panel" },
      h("div", { class: "shots-head" }, h("h2", { class: "panel-title" }, "Shots"), this.countEl),
      h("div", { class: "shots-controls" }, this.sortEl, this.filterEl),
      h("div", { class: "shots-controls" }, this.likeBtn),
      this.similarBox,
      this.listEl);
    new ResizeObserver(() => this._renderRows()).observe(this.listEl);
    return this.el;
  }

  /** The transport bar's button that shows or hides the panel. */
  toggleButton() {
    this.toggleEl = h("button", { class: "btn", type: "button", "aria-pressed": "false", "data-testid": "toggle-shots",
      title: "The Shots panel: every shot with its poster and summary", onclick: () => this.show(!this.open) }, "Shots");
    return this.toggleEl;
  }

  /** Show or hide the panel. @param {boolean} open */
  show(open) {
    if (!this.el || open === this.open) {
      if (open) this.refresh();
      return;
    }
    this.open = open;
    this.el.hidden = !open;
    if (this.toggleEl) this.toggleEl.setAttribute("aria-pressed", String(open));
    if (this.onToggle) this.onToggle(open);
    this.refresh();
  }

  /** Show what changed (the list, the selection, the similarity preview). @param {boolean} [reorder] scroll back to the top */
  refresh(reorder = false) {
    if (!this.el || !this.open) return;
    const { list, similar } = this.actions;
    const shots = this._shots();
    this.countEl.textContent = list ? (shots.length === list.length ? `${list.length}` : `${shots.length} of ${list.length}`) : "";
    this.likeBtn.disabled = !this.actions.selectedShot();
    this.similarBox.hidden = !similar;
    if (similar) {
      const title = /** @type {HTMLElement} */ (this.similarBox.firstElementChild);
      title.textContent = `Shots like the one at ${formatTime(similar.shot.t0 * this.actions.page.tickS)}`;
      this.slider.value = String(Math.round((1 - similar.maxDistance) * 100));
      const n = similar.ids.size;
      this.similarText.textContent = `picks ${n} shot${n === 1 ? "" : "s"} (+ this one)`;
    }
    this.spacer.style.height = `${shots.length * ROW_PX}px`;
    if (reorder) this.listEl.scrollTop = 0;
    this._renderRows();
  }

  /** The shots in the panel's order (kept until the list, order or filter change). */
  _shots() {
    const list = this.actions.list;
    if (!list) return [];
    const key = `${list.revision}|${this.sort}|${this.filter}`;
    if (!this._arranged || this._arranged.key !== key || this._arranged.list !== list) {
      this._arranged = { key, list, shots: arrangeShots(list.shots, this.sort, this.filter) };
    }
    return this._arranged.shots;
  }

  _renderRows() {
    if (!this.open || !this.rowsEl) return;
    const shots = this._shots();
    const top = this.listEl.scrollTop;
    const first = Math.max(0, Math.floor(top / ROW_PX) - OVERSCAN);
    const last = Math.min(shots.length, Math.ceil((top + this.listEl.clientHeight) / ROW_PX) + OVERSCAN);
    const tl = this.actions.page.timeline;
    const sel = tl && tl.selection && tl.selection.ranges ? tl.selection.ranges : [];
    const selected = new Set(sel.map(([a]) => a));
    const preview = this.actions.similar ? this.actions.similar.ids : new Set();
    const rows = [];
    for (let i = first; i < last; i++) rows.push(this._row(shots[i], i, selected.has(shots[i].id), preview.has(shots[i].id)));
    this.rowsEl.replaceChildren(...rows);
    if (!shots.length) this.rowsEl.append(h("p", { class: "shots-empty" }, this.actions.status || "No shot matches."));
  }

  /**
   * @param {import("../data/shot-list.js").Shot} s @param {number} i position in the list
   * @param {boolean} selected @param {boolean} previewed
   */
  _row(s, i, selected, previewed) {
    const tickS = this.actions.page.tickS;
    const pct = (/** @type {number|null} */ v) => (v === null ? "–" : `${Math.round(v * 100)}%`);
    const num = (/** @type {number|null} */ v, /** @type {number} */ d) => (v === null ? "–" : v.toFixed(d));
    const img = h("img", { class: "shot-poster", src: s.poster_url, alt: "", loading: "lazy", decoding: "async", width: 64, height: 36 });
    img.style.background = s.colour || "#1c2230";
    const row = h("div", { class: "shot-row", role: "listitem", "data-testid": "shot-row", "data-id": String(s.id),
      "aria-selected": String(selected), title: `Shot ${formatTime(s.t0 * tickS)} (${s.kind}): click to jump and select it, Shift-click to add it` },
      img,
      h("div", { class: "shot-text" },
        h("div", { class: "shot-time" }, `${formatTime(s.t0 * tickS)} · ${((s.t1 - s.t0) * tickS).toFixed(1)} s`, s.kind !== "cut" ? h("span", { class: "shot-kind" }, s.kind) : ""),
        h("div", { class: "shot-sum" }, `vib ${num(s.vibration_mean, 2)} · fans ${pct(s.fans_share)} · ${num(s.temperature_mean_c, 1)} °C`),
        h("div", { class: "shot-sum" }, `${num(s.loudness_sone, 1)} sone · motion ${num(s.motion, 2)}`)));
    row.style.top = `${i * ROW_PX}px`;
    if (previewed) row.dataset.preview = "true";
    return row;
  }
}
