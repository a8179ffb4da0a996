/**
 * Shots in the editor: the shot list of the revision on screen (loaded after the timeline, never
 * before it), the filmstrip's pictures, the faint shot lines through every lane, selection edges
 * snapping to shot boundaries, selecting shots (one, several, a run), playing one, splitting and
 * merging at the playhead (`shot_split` / `shot_merge` ops) and "select similar shots" with its
 * preview. The Shots panel (panels/shots-panel.js) lists them.
 */

import { h } from "../../core/dom.js";
import { ImageCache } from "../../data/image-cache.js";
import { errorText } from "../../data/http.js";
import { ShotList, similarWithin } from "../../data/shot-list.js";
import { ShotsLane } from "../../lanes/shots.js";
import { ShotsPanel } from "../../panels/shots-panel.js";
import { toast } from "../../panels/widgets.js";

/** a selection edge this close (px) to a shot boundary snaps to it */
export const SNAP_PX = 6;
/** shot lines closer than this (px) to the previous one are left out */
const LINE_GAP_PX = 3;

/** @typedef {import("../../data/shot-list.js").Shot} Shot */

export class ShotActions {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {ShotList|null} */
    this.list = null;
    this.status = "Shots load after the timeline…";
    /** @type {{frame_w: number, frame_h: number, per_tile: number, steps: number[]}|null} */
    this.filmstrip = null;
    this._filmstripAsked = false;
    this._loading = /** @type {number|null} */ (null);
    this.cache = new ImageCache({ onLoad: () => this._picturesIn() });
    /** @type {{shot: Shot, similar: Array<{id: number, distance: number}>, maxDistance: number, ids: Set<number>}|null} */
    this.similar = null;
    /** @type {(() => void)|null} stops a shot playing to its end */
    this._stopAtEnd = null;
    this.panel = new ShotsPanel(this);
  }

  /** The lane, the shot lines and the snapping on the timeline. @param {import("../../core/timeline.js").TimelineView} tl */
  lane(tl) {
    const api = this.page.api;
    const pid = this.page.projectId;
    this.shotsLane = new ShotsLane({
      shots: () => this.list,
      status: () => this.status,
      filmstrip: () => this.filmstrip,
      cache: this.cache,
      posterUrl: (s) => s.poster_url,
      tileUrl: (step, tile) => api.filmstripTileUrl(pid, step, tile),
      preview: () => (this.similar ? this.similar.ids : EMPTY),
      onClick: (s, add) => this.select([s], add),
      onRun: (a, b, add) => this.selectRun(a, b, add),
      onPlay: (s) => this.play(s),
    });
    tl.overlay = (ctx, lane, frame) => this._lines(ctx, lane, frame);
    tl.snapTick = (tick) => {
      if (!this.list) return tick;
      const b = this.list.boundaryNear(tick, SNAP_PX / (tl.pxPerS * tl.tickS));
      return b === null ? tick : b;
    };
    return this.shotsLane;
  }

  /** Right-click on the Shots lane: split / merge / similar. @param {HTMLCanvasElement} canvas */
  wireContextMenu(canvas) {
    canvas.addEventListener("contextmenu", (e) => {
      e.preventDefault();
      const tl = this.page.timeline;
      const shot = this.list && this.list.at(tl.xToTick(e.offsetX));
      this.openMenu(e.clientX, e.clientY, shot);
    });
  }

  /** @param {number} x @param {number} y @param {Shot|null} shot */
  openMenu(x, y, shot) {
    this.closeMenu();
    const item = (/** @type {string} */ text, /** @type {string} */ testid, /** @type {() => void} */ fn) =>
      h("button", { type: "button", class: "menu-item", role: "menuitem", "data-testid": testid, onclick: () => { this.closeMenu(); fn(); } }, text);
    const menu = h("div", { class: "context-menu", role: "menu", "data-testid": "shots-menu" },
      item("Split the shot at the playhead (S)", "shots-menu-split", () => this.split()),
      item("Merge the shot at the playhead with the next (M)", "shots-menu-merge", () => this.merge()));
    if (shot) {
      menu.append(item("Select this shot", "shots-menu-select", () => this.select([shot], false)),
        item("Select shots like this…", "shots-menu-similar", () => this.openSimilar(shot)));
    }
    menu.style.left = `${x}px`;
    menu.style.top = `${y}px`;
    document.body.append(menu);
    this.menuEl = menu;
    const close = (/** @type {Event} */ ev) => {
      if (!menu.contains(/** @type {Node} */ (ev.target)) || (ev instanceof KeyboardEvent && ev.key === "Escape")) this.closeMenu();
    };
    setTimeout(() => {
      document.addEventListener("pointerdown", close, true);
      document.addEventListener("keydown", close, true);
    });
    this._menuOff = () => {
      document.removeEventListener("pointerdown", close, true);
      document.removeEventListener("keydown", close, true);
    };
    /** @type {HTMLElement} */ (menu.firstElementChild).focus();
  }

  closeMenu() {
    if (this.menuEl) this.menuEl.remove();
    if (this._menuOff) this._menuOff();
    this.menuEl = null;
    this._menuOff = null;
  }

  /** Load the shot list of a revision (after the timeline of that revision is on screen). @param {number} revision */
  async load(revision) {
    const page = this.page;
    if ((this.list && this.list.revision === revision) || this._loading === revision) return;
    this._loading = revision;
    this._loadFilmstrip();
    let doc;
    try {
      doc = await page.api.shots(page.projectId);
    } catch (err) {
      this.status = `No shots: ${errorText(err)}`;
      this._loading = null;
      if (!page.disposed) page.timeline.invalidate("shots");
      return;
    }
    this._loading = null;
    if (page.disposed || (this.list && this.list.revision > doc.revision)) return;
    this.list = new ShotList(doc);
    this.status = this.list.length ? "" : "No shots";
    if (this.similar && !this.list.get(this.similar.shot.id)) this.closeSimilar();
    page.timeline.invalidate();
    page.edits.updateToolbar();
    this.panel.refresh();
  }

  /** The filmstrip's sizes, once; shot posters stand in while it is not served. */
  async _loadFilmstrip() {
    if (this._filmstripAsked) return;
    this._filmstripAsked = true;
    try {
      this.filmstrip = await this.page.api.filmstrip(this.page.projectId);
    } catch {
      this.filmstrip = null;
      this._filmstripAsked = false; // asked again with the next shot list
      return;
    }
    if (!this.page.disposed) this.page.timeline.invalidate("shots");
  }

  _picturesIn() {
    if (this.page.disposed) return;
    this.page.timeline.invalidate("shots");
  }

  /**
   * Faint lines at the shot boundaries through every lane (a brighter one on the Shots lane).
   * @param {CanvasRenderingContext2D} ctx
   * @param {import("../../core/timeline.js").Lane} lane
   * @param {import("../../core/timeline.js").LaneFrame} frame
   */
  _lines(ctx, lane, { width, height, view }) {
    const list = this.list;
    if (!list || list.length < 2) return;
    const i0 = list.indexAt(Math.floor(view.startS / view.tickS));
    const i1 = list.indexAt(Math.ceil(view.endS / view.tickS));
    ctx.save();
    ctx.strokeStyle = lane.id === "shots" ? "rgba(11, 13, 18, 0.9)" : "rgba(226, 232, 240, 0.13)";
    ctx.lineWidth = 1;
    ctx.beginPath();
    let last = -Infinity;
    for (let i = Math.max(1, i0); i <= i1; i++) {
      const x = Math.round(view.tickToX(list.starts[i])) + 0.5;
      if (x < 0 || x > width || x - last < LINE_GAP_PX) continue;
      ctx.moveTo(x, 0);
      ctx.lineTo(x, height);
      last = x;
    }
    ctx.stroke();
    ctx.restore();
  }

  /** The lanes an edit applies to now (the chips). */
  _lanes() {
    const tl = this.page.timeline;
    return tl.selection ? tl.selection.lanes : tl.defaultLanes;
  }

  /**
   * Select shots (their whole ranges); `add` keeps the shots selected before, and takes out a
   * shot that was selected already.
   * @param {Shot[]} shots @param {boolean} add
   */
  select(shots, add) {
    const tl = this.page.timeline;
    const sel = tl.selection;
    /** @type {Array<[number, number]>} */
    let ranges = add && sel && sel.ranges ? sel.ranges.map(([a, b]) => [a, b]) : [];
    for (const s of shots) {
      const had = ranges.some(([a, b]) => a === s.t0 && b === s.t1);
      if (had && add && shots.length === 1) ranges = ranges.filter(([a, b]) => !(a === s.t0 && b === s.t1));
      else if (!had) ranges.push([s.t0, s.t1]);
    }
    if (!ranges.length) {
      tl.setSelection(null);
      return;
    }
    tl.setSelection({ t0: 0, t1: 1, lanes: this._lanes(), ranges });
  }

  /** Every shot from `a` to `b` (either order). @param {Shot} a @param {Shot} b @param {boolean} add */
  selectRun(a, b, add) {
    const list = this.list;
    if (!list) return;
    const [i0, i1] = [list.byId.get(a.id) ?? 0, list.byId.get(b.id) ?? 0].sort((p, q) => p - q);
    this.select(list.shots.slice(i0, i1 + 1), add);
  }

  /** Select a shot and bring it into view with the playhead at its start. @param {Shot} shot @param {boolean} add */
  jump(shot, add) {
    this.select([shot], add);
    this.page.media.seek(shot.t0 * this.page.tickS);
  }

  /** Play one shot from its start; playback pauses at its end. @param {Shot} shot */
  async play(shot) {
    const media = this.page.media;
    const player = media.player;
    if (this._stopAtEnd) this._stopAtEnd();
    const endS = shot.t1 * this.page.tickS;
    media.seek(shot.t0 * this.page.tickS);
    const offs = [
      player.on("time", ({ timeS, playing }) => {
        if (playing && timeS >= endS - 1e-3) {
          stop();
          player.pause();
          media.seek(endS - this.page.tickS / 2);
        }
      }),
      player.on("state", ({ playing }) => {
        if (!playing && started) stop();
      }),
    ];
    let started = false;
    const stop = () => {
      for (const off of offs) off();
      if (this._stopAtEnd === stop) this._stopAtEnd = null;
    };
    this._stopAtEnd = stop;
    if (!player.playing) await media.togglePlay();
    started = true;
  }

  /** The shot holding the playhead. */
  _atPlayhead() {
    const { data, media } = this.page;
    if (!this.list || !data) return null;
    return { tick: data.tickAt(media.player.currentTime), shot: this.list.at(data.tickAt(media.player.currentTime)) };
  }

  /** Split the shot at the playhead there (one `shot_split` op). */
  split() {
    const at = this._atPlayhead();
    if (!at || !at.shot) return toast("There are no shots to split yet.", "warn");
    if (at.shot.t0 === at.tick) return toast("A shot already starts at the playhead: move it inside a shot to split it.", "warn");
    return this.page.edits.submit({ op: "shot_split", t: at.tick });
  }

  /** Merge the shot at the playhead with the next one (one `shot_merge` op). */
  merge() {
    const at = this._atPlayhead();
    if (!at || !at.shot) return toast("There are no shots to merge yet.", "warn");
    const next = this.list.at(at.shot.t1);
    if (!next || next.id === at.shot.id) return toast("The shot at the playhead is the last: there is no next one to merge with.", "warn");
    return this.page.edits.submit({ op: "shot_merge", shots: [at.shot.id, next.id] });
  }

  /** The one selected shot (a selection of exactly one whole shot), else null. */
  selectedShot() {
    const sel = this.page.timeline.selection;
    if (!sel || !sel.ranges || sel.ranges.length !== 1 || !this.list) return null;
    const s = this.list.get(sel.ranges[0][0]);
    return s && s.t1 === sel.ranges[0][1] ? s : null;
  }

  /** Ask for the shots like `shot`; the panel shows the slider and the count. @param {Shot} shot */
  async openSimilar(shot) {
    const page = this.page;
    let got;
    try {
      got = await page.api.similarShots(page.projectId, shot.id);
    } catch (err) {
      toast(`Could not find similar shots: ${errorText(err)}`, "warn");
      return;
    }
    if (page.disposed) return;
    const maxDistance = this.similar ? this.similar.maxDistance : 0.2;
    this.similar = { shot, similar: got.similar, maxDistance, ids: new Set() };
    this.previewSimilar(maxDistance);
    this.panel.show(true);
    this.panel.slider.focus(); // the keyboard goes on in the box (Escape closes it)
  }

  /** Mark the shots within `maxDistance` (0..1) of the chosen one; nothing changes. @param {number} maxDistance */
  previewSimilar(maxDistance) {
    if (!this.similar) return;
    this.similar.maxDistance = maxDistance;
    this.similar.ids = new Set(similarWithin(this.similar.similar, maxDistance));
    this.page.timeline.invalidate("shots");
    this.panel.refresh();
  }

  /** Select the chosen shot and the previewed ones. */
  applySimilar() {
    const sim = this.similar;
    if (!sim || !this.list) return;
    const shots = [sim.shot, ...[...sim.ids].map((id) => this.list.get(id)).filter((s) => s !== null)];
    this.closeSimilar();
    this.select(/** @type {Shot[]} */ (shots), false);
    toast(`Selected ${shots.length} shots: Set, Scale, Clear, the fades and Paste now change all of them at once.`);
  }

  closeSimilar() {
    this.similar = null;
    this.page.timeline.invalidate("shots");
    this.panel.refresh();
  }

  /** What the debug handle reports. */
  debug() {
    return {
      count: this.list ? this.list.length : null,
      revision: this.list ? this.list.revision : null,
      filmstrip: !!this.filmstrip,
      step: this.shotsLane ? this.shotsLane.step : 0,
      pictures: this.cache.stats(),
      similar: this.similar ? { shot: this.similar.shot.id, maxDistance: this.similar.maxDistance, ids: [...this.similar.ids].sort((a, b) => a - b) } : null,
      panelOpen: this.panel.open,
    };
  }

  destroy() {
    this.closeMenu();
    if (this._stopAtEnd) this._stopAtEnd();
    this.cache.dispose();
  }
}

const EMPTY = new Set();
