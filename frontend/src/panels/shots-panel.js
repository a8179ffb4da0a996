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
    /** position of the keyboard's active row in the panel's order */
    this.active = 0;
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
    this.similarBox = h("div", { class: "shots-similar", hidden: true, role: "group", "aria-label": "Shots like this", "data-testid": "shots-similar" },
      h("div", { class: "shots-similar-row" }, h("span", { class: "shots-similar-title", "data-testid": "shots-similar-title" }), this.similarText),
      h("div", { class: "shots-similar-row" }, this.slider,
        h("button", { class: "btn btn-small btn-primary", type: "button", "data-testid": "shots-similar-apply", title: "Select them and the chosen shot", onclick: () => this._closing(() => this.actions.applySimilar(), this.listEl) }, "Select"),
        h("button", { class: "btn btn-small", type: "button", "data-testid": "shots-similar-cancel", "aria-label": "Cancel", title: "Cancel (Escape): nothing changes", onclick: () => this._closing(() => this.actions.closeSimilar(), this.likeBtn) }, "✕")));
    this.spacer = h("div", { class: "shots-spacer" });
    this.rowsEl = h("div", { class: "shots-rows" });
    this.listEl = h("div", { class: "shots-list", tabindex: "0", role: "listbox", "aria-multiselectable": "true",
      "aria-label": "Shots: arrows move, Enter or Space jumps there and selects it, Shift adds it", "data-testid": "shots-list" }, this.spacer, this.rowsEl);
    this.listEl.addEventListener("scroll", () => this._renderRows());
    this.listEl.addEventListener("click", (e) => {
      const row = /** @type {HTMLElement|null} */ (/** @type {HTMLElement} */ (e.target).closest(".shot-row"));
      const list = this.actions.list;
      const shot = row && list ? list.get(Number(row.dataset.id)) : null;
      if (!shot) return;
      this.active = this._shots().indexOf(shot);
      this.actions.jump(shot, e.shiftKey);
    });
    this.listEl.addEventListener("keydown", (e) => this._key(e));
    this.listEl.addEventListener("focus", () => this._activate(this.active));
    this.el = h("section", { class: "panel shots-panel", hidden: true, "aria-label": "Shots", "data-testid": "shots-panel" },
      h("div", { class: "shots-head" }, h("h2", { class: "panel-title" }, "Shots"), this.countEl, this.likeBtn),
      h("div", { class: "shots-controls" }, this.sortEl, this.filterEl),
      this.similarBox,
      this.listEl);
    this.el.addEventListener("keydown", (e) => {
      if (e.key !== "Escape" || !this.actions.similar) return;
      e.preventDefault();
      e.stopPropagation(); // Escape closes the box and keeps the selection (the chair's STOP listens before this)
      this._closing(() => this.actions.closeSimilar(), this.likeBtn);
    });
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
      const title = /** @type {HTMLElement} */ (this.similarBox.querySelector(".shots-similar-title"));
      title.textContent = `Like ${formatTime(similar.shot.t0 * this.actions.page.tickS)}:`;
      this.slider.value = String(Math.round((1 - similar.maxDistance) * 100));
      const n = similar.ids.size;
      this.similarText.textContent = `picks ${n} shot${n === 1 ? "" : "s"} (+ this one)`;
    }
    this.spacer.style.height = `${shots.length * ROW_PX}px`;
    if (reorder) {
      this.listEl.scrollTop = 0;
      this.active = 0;
    }
    this._renderRows();
  }

  /** Run `close` (the similar box closes), then focus `next` if the focus was in the box. @param {() => void} close @param {HTMLElement} next */
  _closing(close, next) {
    const inBox = this.similarBox.contains(document.activeElement);
    close();
    if (inBox) next.focus();
  }

  /** The list's keys: arrows, Home / End, Page Up / Down move; Enter or Space jumps (Shift: adds). @param {KeyboardEvent} e */
  _key(e) {
    const shots = this._shots();
    if (!shots.length || e.ctrlKey || e.metaKey || e.altKey) return;
    const page = Math.max(1, Math.floor(this.listEl.clientHeight / ROW_PX) - 1);
    const moves = /** @type {Record<string, number>} */ ({ ArrowDown: 1, ArrowUp: -1, PageDown: page, PageUp: -page });
    if (e.key in moves) this._activate(this.active + moves[e.key]);
    else if (e.key === "Home") this._activate(0);
    else if (e.key === "End") this._activate(shots.length - 1);
    else if (e.key === "Enter" || e.key === " ") this.actions.jump(shots[Math.min(this.active, shots.length - 1)], e.shiftKey);
    else return;
    e.preventDefault();
    e.stopPropagation(); // the editor's keys (Space plays, arrows and Home / End seek) stay out of the list
  }

  /** Make row `i` the active one and scroll it into view. @param {number} i */
  _activate(i) {
    const n = this._shots().length;
    this.active = Math.max(0, Math.min(n - 1, i));
    const top = this.active * ROW_PX;
    const before = this.listEl.scrollTop;
    if (top < before) this.listEl.scrollTop = top;
    else if (top + ROW_PX > before + this.listEl.clientHeight) this.listEl.scrollTop = top + ROW_PX - this.listEl.clientHeight;
    if (this.listEl.scrollTop !== before) this._renderRows();
    else this._markActive(); // rows kept: a click whose press focused the list still lands on its row
  }

  /** Mark the active row among those drawn, and name it as the list's active descendant. */
  _markActive() {
    const shots = this._shots();
    const id = this.active < shots.length ? String(shots[this.active].id) : null;
    for (const row of /** @type {NodeListOf<HTMLElement>} */ (this.rowsEl.querySelectorAll(".shot-row"))) {
      if (row.dataset.id === id) row.dataset.active = "true";
      else delete row.dataset.active;
    }
    if (id === null) this.listEl.removeAttribute("aria-activedescendant");
    else this.listEl.setAttribute("aria-activedescendant", `shot-row-${id}`);
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
    this._markActive();
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
    const row = h("div", { class: "shot-row", role: "option", id: `shot-row-${s.id}`, "data-testid": "shot-row", "data-id": String(s.id),
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
