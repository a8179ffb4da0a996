/**
 * The editor screen: the video with the fan-grid overlay and the chair diagram beside a
 * multi-lane timeline sharing one playhead, the editing toolbar, thresholds, regenerate and
 * export. It wires the parts together and owns the three kinds of state:
 *
 * - edits (saved and undoable): the server's op list, through EditSession;
 * - view settings (saved, not undoable): zoom, scroll, hidden lanes, overlay toggle -> PATCH view;
 * - playback position and connection status (neither): Player and the status line.
 */

import { ApiError } from "../../data/api.js";
import { ChairDiagram } from "../../chair/diagram.js";
import { ChairSync } from "../../chair/sync.js";
import { FrameLoop } from "../../core/frameloop.js";
import { TimelineView } from "../../core/timeline.js";
import { h, promptDialog, toast } from "../../core/dom.js";
import { Clipboard, clearOp, fadeOp, markerAddOp, markerDeleteOp, markerUpdateOp, scaleOp, setOp, tempPointsOp } from "../../data/edit-ops.js";
import { FanOverlay } from "../../chair/fan-overlay.js";
import { formatTime } from "../../data/format.js";
import { EditSession, errorText } from "../../data/edit-session.js";
import { ActuatorsLane } from "../../lanes/actuators.js";
import { FeatureLane } from "../../lanes/features.js";
import { FansLane } from "../../lanes/fans.js";
import { MarkersLane } from "../../lanes/markers.js";
import { TemperatureLane } from "../../lanes/temperature.js";
import { VibrationDetailLane } from "../../lanes/vibration-detail.js";
import { WaveformLane } from "../../lanes/waveform.js";
import { ChairPanel } from "../../chair/panel.js";
import { exportMenu } from "../../panels/export-menu.js";
import { JobProgress } from "../../panels/job-progress.js";
import { regenerateDialog } from "../../panels/regenerate.js";
import { ThresholdsPanel } from "../../panels/thresholds.js";
import { EditToolbar } from "../../panels/toolbar.js";
import { Player } from "../../core/player.js";
import { ACTUATOR_IDS, AUDIO_FEATURES, FIRST_BLOCKS, TimelineData } from "../../data/timeline-data.js";

const VIEW_SAVE_DELAY_MS = 600;
const ZOOM_STEP = 1.5;

/**
 * @typedef {{
 *   config: Record<string, any>,
 *   api: import("../../data/api.js").Api,
 * }} EditorContext
 */
/**
 * @template T
 * @typedef {Promise<{value: T}|{error: unknown}>} Settled
 */
/**
 * @typedef {{project: Settled<import("../../data/api.js").Project>, edits: Settled<import("../../data/api.js").EditList>,
 *   bin: Settled<ArrayBuffer>|null}} EditorLoads
 */

/**
 * The requests the editor needs first, all at once. `early` holds the same requests when
 * index.html started them before the modules loaded. Failures are kept, not thrown, until the
 * editor reads them.
 * @param {import("../../data/api.js").Api} api
 * @param {string} projectId
 * @param {{project: Promise<Response>, edits: Promise<Response>, bin: Promise<Response>}|null} [early]
 * @returns {EditorLoads}
 */
export function startEditorLoads(api, projectId, early = null) {
  /** @template T @param {Promise<T>} p @returns {Settled<T>} */
  const settle = (p) => p.then((value) => ({ value }), (error) => ({ error }));
  if (early) {
    const base = `/api/projects/${encodeURIComponent(projectId)}`;
    return {
      project: settle(api.readJson(early.project, `GET ${base}`)),
      edits: settle(api.readJson(early.edits, `GET ${base}/edits`)),
      bin: settle(api.readBuffer(early.bin, `GET ${api.timelineBinPath(projectId, "composed", FIRST_BLOCKS)}`)),
    };
  }
  return {
    project: settle(api.project(projectId)),
    edits: settle(api.edits(projectId)),
    bin: settle(api.timelineBin(projectId, "composed", FIRST_BLOCKS)),
  };
}

export class EditorPage {
  /**
   * @param {HTMLElement} host
   * @param {EditorContext} ctx
   * @param {string} projectId
   */
  constructor(host, ctx, projectId) {
    this.host = host;
    this.api = ctx.api;
    this.config = ctx.config;
    this.projectId = projectId;
    this.loop = new FrameLoop();
    /** @type {TimelineData|null} */
    this.data = null;
    /** @type {import("../../data/api.js").Project|null} */
    this.project = null;
    /** @type {EditSession|null} */
    this.session = null;
    /** Jobs being followed (progress shown); a threshold re-derive may bring a background one. */
    this.jobsFollowed = 0;
    /** @type {Record<string, number>} */
    this.thresholds = { ...(this.config.default_thresholds || {}) };
    /** @type {Array<{id: string, t_s: number, label: string}>} */
    this.markers = [];
    /** @type {string|null} */
    this.selectedMarker = null;
    this.clipboard = new Clipboard();
    /** @type {Array<[number, number]>} */
    this.points = [];
    this.lastTick = -1;
    /** @type {number|null} revision of the timeline last drawn on the lanes */
    this.drawnRevision = null;
    this.disposed = false;
    /** @type {Array<() => void>} */
    this.cleanups = [];
    /** Milliseconds from `start` (performance.now() when the editor began opening) to each step. */
    this.timing = { start: performance.now(), projectLoaded: NaN, binFetched: NaN, dataLoaded: NaN, firstRender: NaN, waveformLoaded: NaN };
    /** @type {ReturnType<typeof setTimeout>|null} */
    this._viewTimer = null;
    this._restoringView = false;
  }

  // ------------------------------------------------------------------- open
  /**
   * @param {EditorLoads} [loads] the first requests, when the caller started them already
   */
  async open(loads = startEditorLoads(this.api, this.projectId)) {
    this._firstLoads = loads;
    this._buildShell();
    const got = await loads.project;
    if ("error" in got) {
      const err = got.error;
      this._fatal(err instanceof ApiError && err.status === 404 ? "This project does not exist (it may have been deleted)." : errorText(err));
      return;
    }
    const project = got.value;
    this.project = project;
    this.timing.projectLoaded = performance.now() - this.timing.start;
    this.nameEl.textContent = project.name;
    document.title = `${project.name} · autohaptics`;
    if (project.params && project.params.thresholds) this.thresholds = { ...project.params.thresholds };
    const durationS = project.duration_s || (project.n_ticks || 1) * this.tickS;
    this._buildWorkspace(durationS);
    this._restoreView(project.view || {});
    const tasks = [this._loadEdits(), this._loadWaveform(project)];
    if (project.has_timeline) {
      tasks.push(this.reloadTimeline());
    } else {
      loads.bin = null; // a 404 now; the timeline is fetched when a job makes one
      this._setNoTimeline(project);
      this._attachMedia();
    }
    await Promise.all(tasks);
    if (project.job && (project.job.status === "queued" || project.job.status === "running")) this._followJob(project.job);
  }

  get tickS() {
    return Number(this.config.tick_s) || 0.1;
  }

  /** Temperature range for drawing: the generator's range, widened to the data. */
  tempRange() {
    const t = this.config.temperature || {};
    const lo = Math.min(Number(t.low_c ?? 30), this.data ? this.data.temperatureMin : Infinity);
    const hi = Math.max(Number(t.high_c ?? 55), this.data ? this.data.temperatureMax : -Infinity);
    return { lo, hi, neutral: Number(t.neutral_c ?? 33) };
  }

  // ------------------------------------------------------------------ build
  _buildShell() {
    this.nameEl = h("h1", { class: "project-name", "data-testid": "project-name" }, "…");
    this.saveEl = h("span", { class: "save-state", role: "status", "aria-live": "polite", "data-testid": "save-state" }, "");
    this.undoBtn = h("button", { class: "btn", type: "button", disabled: true, title: "Undo (Ctrl+Z)", "data-testid": "undo", onclick: () => this.undo() }, "Undo");
    this.redoBtn = h("button", { class: "btn", type: "button", disabled: true, title: "Redo (Ctrl+Shift+Z)", "data-testid": "redo", onclick: () => this.redo() }, "Redo");
    this.regenBtn = h("button", { class: "btn", type: "button", "data-testid": "regenerate", onclick: () => this.regenerate() }, "Regenerate…");
    this.importInput = h("input", { type: "file", accept: ".json,.csv,application/json,text/csv", class: "visually-hidden", "data-testid": "import-input", "aria-label": "Timeline file to import" });
    this.importInput.addEventListener("change", () => {
      const f = this.importInput.files && this.importInput.files[0];
      this.importInput.value = "";
      if (f) this.importTimeline(f);
    });
    this.importBtn = h("button", { class: "btn", type: "button", "data-testid": "import", title: "Replace the tracks by a timeline file (JSON or CSV); undoable", onclick: () => this.importInput.click() }, "Import…");
    this.exportSlot = h("div", { class: "export-slot" });
    this.chairIndicator = h("span", { class: "badge chair-indicator", "data-state": "idle", "data-testid": "chair-indicator", title: "Chair connection" }, "Chair off");
    this.stopBtn = h(
      "button",
      { class: "btn btn-danger btn-stop", type: "button", "data-testid": "chair-stop", "aria-keyshortcuts": "Escape", title: "Stop the chair: every output off now (Escape)", onclick: () => this.chairStop() },
      "■ Stop chair",
    );
    const header = h(
      "header",
      { class: "topbar" },
      h("a", { class: "btn btn-ghost", href: "#/", "data-testid": "back" }, "← Projects"),
      this.nameEl,
      this.saveEl,
      h("div", { class: "spacer" }),
      this.chairIndicator,
      this.stopBtn,
      this.undoBtn,
      this.redoBtn,
      this.regenBtn,
      this.importBtn,
      this.importInput,
      this.exportSlot,
    );
    this.main = h("main", { class: "editor", "data-testid": "editor" });
    this.host.replaceChildren(header, this.main);
    this.exportSlot.append(exportMenu(this.api, this.projectId, this._exportFormats()));
    // STOP wins over everything else Escape does, wherever the focus is (a text field, a dialog).
    const onEscape = (/** @type {KeyboardEvent} */ e) => {
      if (e.key === "Escape" && this.chairPanel && this.chairPanel.active) this.chairStop();
    };
    document.addEventListener("keydown", onEscape, true);
    this.cleanups.push(() => document.removeEventListener("keydown", onEscape, true));
  }

  /** The formats /api/config lists ({name, description}), else JSON and CSV. */
  _exportFormats() {
    const listed = this.config.export_formats;
    if (Array.isArray(listed) && listed.length) {
      return listed
        .map((f) => (typeof f === "string" ? { name: f, description: "" } : { name: String(f.name || ""), description: String(f.description || "") }))
        .filter((f) => f.name);
    }
    return [{ name: "json", description: "" }, { name: "csv", description: "" }];
  }

  /** @param {number} durationS */
  _buildWorkspace(durationS) {
    // The media source is set once the timeline is drawn (_attachMedia), so the video's first range
    // requests do not compete with timeline.bin for the server.
    this.video = h("video", { class: "video", preload: "auto", playsinline: true, "data-testid": "video" });
    this.overlayCanvas = h("canvas", { class: "fan-overlay", hidden: true, "data-testid": "fan-overlay", "aria-label": "Fan grid at the playhead" });
    const videoWrap = h("div", { class: "video-wrap" }, this.video, this.overlayCanvas);
    this.fanOverlay = new FanOverlay(this.overlayCanvas, this.video);
    this.player = new Player(this.video, { durationS, frameLoop: this.loop });
    this.chairHost = h("div", { class: "chair" });
    const layout = (this.config.layout && this.config.layout.actuators) || ACTUATOR_IDS.map((id) => ({ id, x: 0.5, y: 0.5, zone: "back" }));
    this.chair = new ChairDiagram(this.chairHost, { actuators: layout, temperature: this.tempRange() });
    const features = (this.config.features || AUDIO_FEATURES).filter((/** @type {string} */ f) => AUDIO_FEATURES.includes(f));
    this.thresholdPanel = new ThresholdsPanel(features, {
      onInput: (name, v) => this._thresholdInput(name, v),
      onCommit: (name, v) => this.commitThreshold(name, v),
    });
    for (const [n, v] of Object.entries(this.thresholds)) this.thresholdPanel.set(n, v);
    this.paramsInfo = h("p", { class: "params-info", "data-testid": "params-info" });
    const chairPanel = h("section", { class: "panel", "aria-labelledby": "chair-title" }, h("h2", { class: "panel-title", id: "chair-title" }, "At the playhead"), this.chairHost);
    this.chairPanel = new ChairPanel(this.api, { projectId: this.projectId, range: () => this._pushRange() });
    this.chairSync = new ChairSync(this.api, this.projectId, this.player, { onError: (m) => toast(`The chair did not follow: ${m}`, "warn") });
    this.cleanups.push(
      this.chairPanel.on("status", ({ status, active }) => {
        this.chairSync.setActive(active);
        this.chairIndicator.dataset.state = status.state;
        this.chairIndicator.textContent = status.state === "connected" ? "Chair on" : status.state === "reconnecting" ? "Chair reconnecting…" : "Chair off";
      }),
      () => this.chairSync.destroy(),
      () => this.chairPanel.destroy(),
    );
    const side = h("aside", { class: "side" }, this.thresholdPanel.el, this.paramsInfo, this.chairPanel.el);
    this.jobSlot = h("div", { class: "job-slot", hidden: true, "data-testid": "job-slot" });
    this.notice = h("div", { class: "notice", hidden: true, role: "status", "data-testid": "editor-notice" });

    this.playBtn = h("button", { class: "btn btn-primary btn-play", type: "button", "data-testid": "play", "aria-label": "Play (Space)", onclick: () => this.togglePlay() }, "▶");
    this.timeEl = h("span", { class: "time", "data-testid": "time" }, `0:00.0 / ${formatTime(durationS)}`);
    this.overlayBtn = h("button", { class: "btn", type: "button", "aria-pressed": "false", "data-testid": "toggle-fan-overlay", onclick: () => this.setOverlay(!this.fanOverlay.visible) }, "Fan grid");
    this.followBtn = h("button", { class: "btn", type: "button", "aria-pressed": "true", "data-testid": "toggle-follow", title: "Keep the playhead in view while playing", onclick: () => this.setFollow(!this.timeline.follow) }, "Follow");
    const zoomOut = h("button", { class: "btn", type: "button", "aria-label": "Zoom out (-)", "data-testid": "zoom-out", onclick: () => this.timeline.zoomBy(1 / ZOOM_STEP) }, "−");
    const zoomFit = h("button", { class: "btn", type: "button", "aria-label": "Show the whole timeline (0)", "data-testid": "zoom-fit", onclick: () => this.timeline.fit() }, "Fit");
    const zoomIn = h("button", { class: "btn", type: "button", "aria-label": "Zoom in (+)", "data-testid": "zoom-in", onclick: () => this.timeline.zoomBy(ZOOM_STEP) }, "+");
    this.lanesMenu = h("details", { class: "menu", "data-testid": "lanes-menu" }, h("summary", { class: "btn" }, "Lanes"));
    const keys = [
      ["Space", "play / pause"], ["← →", "step one tick (Shift: one second)"], ["Home / End", "start / end"],
      ["+ / − / 0", "zoom in / out / whole film"], ["Ctrl+wheel, pinch", "zoom at the pointer"], ["Wheel", "pan"],
      ["Alt+drag, middle drag", "pan"], ["Drag on lanes", "select a range (across heat-map rows: several actuators)"],
      ["Ctrl+Z / Ctrl+Shift+Z", "undo / redo"], ["Ctrl+C / Ctrl+V", "copy / paste at the playhead"],
      ["Delete", "clear the selection, or delete the selected marker"], ["Escape", "stop the chair (when connected); drop the selection or the points"],
    ];
    const keysMenu = h(
      "details",
      { class: "menu", "data-testid": "keys-menu" },
      h("summary", { class: "btn", "aria-label": "Keyboard and mouse shortcuts" }, "Keys"),
      h("dl", { class: "menu-list keys-list" }, ...keys.flatMap(([k, what]) => [h("dt", {}, k), h("dd", {}, what)])),
    );
    const transport = h(
      "div",
      { class: "transport", role: "group", "aria-label": "Playback and view" },
      this.playBtn,
      this.timeEl,
      h("div", { class: "btn-group", role: "group", "aria-label": "Zoom" }, zoomOut, zoomFit, zoomIn),
      this.followBtn,
      this.overlayBtn,
      this.lanesMenu,
      keysMenu,
    );

    this.toolbar = new EditToolbar({
      tool: (t) => this.setTool(t),
      toggleLane: (lane) => this.toggleLane(lane),
      set: (v) => this._selectionOp((sel) => setOp(sel, v)),
      scale: (f) => this._selectionOp((sel) => scaleOp(sel, f)),
      clear: () => this._selectionOp((sel) => clearOp(sel)),
      fade: (k) => this._selectionOp((sel) => fadeOp(sel, k)),
      copy: () => this.copy(),
      paste: () => this.paste(),
      applyPoints: () => this.applyPoints(),
      discardPoints: () => this.setPoints([]),
      addMarker: () => this.addMarker(this.player.currentTime),
      renameMarker: () => this.selectedMarker && this.renameMarker(this.selectedMarker),
      deleteMarker: () => this.selectedMarker && this.deleteMarker(this.selectedMarker),
    });

    this.timelineHost = h("div", { class: "timeline-host" });
    this.main.append(
      h("section", { class: "stage" }, videoWrap, chairPanel, side),
      this.jobSlot,
      this.notice,
      transport,
      this.toolbar.el,
      this.timelineHost,
    );

    const tl = new TimelineView(this.timelineHost, { durationS, tickS: this.tickS, frameLoop: this.loop });
    this.timeline = tl;
    this._addLanes(features);
    this._wireEvents();
    this._updateToolbar();
    this._updateParamsInfo();
    this.chairPanel.open();
  }

  /** What "Push" sends to the chair: the selection, else the whole film (seconds). */
  _pushRange() {
    const tl = this.timeline;
    const sel = tl && tl.selection;
    if (sel) return { startS: sel.t0 * this.tickS, endS: sel.t1 * this.tickS, label: "selection" };
    return { startS: 0, endS: tl ? tl.durationS : 0, label: "whole film" };
  }

  /** STOP the chair: every output off now, the player paused, queued playback reports dropped. */
  async chairStop() {
    const racing = this.chairSync ? this.chairSync.halt() : null;
    const stop = () => (this.chairPanel ? this.chairPanel.stop() : this.api.chairStop().catch((err) => toast(`STOP failed: ${errorText(err)}`, "error")));
    const stopping = stop();
    if (this.player && this.player.playing) this.player.pause();
    await stopping;
    if (racing) {
      // A play report already on its way may reach the server after the STOP and restart the
      // chair: once it has landed, STOP again.
      await racing;
      await stop();
    }
  }

  /** @param {string[]} features */
  _addLanes(features) {
    const data = () => this.data;
    const tl = this.timeline;
    this.waveformLane = new WaveformLane();
    tl.addLane(this.waveformLane);
    this.featureLanes = features.map((name) =>
      new FeatureLane(name, {
        data,
        threshold: (n) => (n in this.thresholds ? this.thresholds[n] : null),
        onInput: (n, v) => this._thresholdInput(n, v),
        onCommit: (n, v) => this.commitThreshold(n, v),
        onCancel: (n) => this._thresholdCancel(n),
      }));
    for (const lane of this.featureLanes) tl.addLane(lane);
    const zones = /** @type {Record<string, string>} */ ({});
    for (const a of (this.config.layout && this.config.layout.actuators) || []) zones[a.id] = a.body || a.zone;
    this.actuatorsLane = new ActuatorsLane({ data, zones });
    tl.addLane(this.actuatorsLane);
    this.detailLane = new VibrationDetailLane({
      data,
      onPencil: (op) => this._submitStroke(op, this.detailLane),
      onChange: () => {
        tl.invalidate("detail");
        this._scheduleViewSave();
      },
    });
    tl.addLane(this.detailLane);
    this.temperatureLane = new TemperatureLane({
      data,
      range: () => this.tempRange(),
      onPencil: (op) => this._submitStroke(op, this.temperatureLane),
      onPointsChange: (pts) => {
        this.points = pts.map(([t, c]) => [t, c]);
        this._updateToolbar();
      },
    });
    tl.addLane(this.temperatureLane);
    this.fansLane = new FansLane({ data });
    tl.addLane(this.fansLane);
    this.markersLane = new MarkersLane({
      markers: () => this.markers,
      selected: () => this.selectedMarker,
      onSelect: (id) => this.selectMarker(id),
      onMove: (id, t) => this.moveMarker(id, t),
      onAdd: (t) => this.addMarker(t),
      onRename: (id) => this.renameMarker(id),
    });
    tl.addLane(this.markersLane);

    const list = h("div", { class: "menu-list menu-checks" });
    for (const { lane } of tl.lanes) {
      const cb = h("input", { type: "checkbox", checked: true, "data-testid": `lane-toggle-${lane.id}` });
      cb.addEventListener("change", () => {
        tl.setLaneVisible(lane.id, cb.checked);
        this._scheduleViewSave();
      });
      list.append(h("label", { class: "menu-check" }, cb, lane.label));
    }
    this.lanesMenu.append(list);
  }

  _wireEvents() {
    const tl = this.timeline;
    const player = this.player;
    this.cleanups.push(
      player.on("time", ({ timeS, playing }) => this._onTime(timeS, playing)),
      player.on("state", ({ playing }) => {
        this.playBtn.textContent = playing ? "❚❚" : "▶";
        this.playBtn.setAttribute("aria-label", playing ? "Pause (Space)" : "Play (Space)");
      }),
      player.on("media-error", ({ message }) => this._showNotice(message)),
      tl.on("scrub", ({ timeS }) => player.seek(timeS)),
      tl.on("seek", ({ timeS }) => player.seek(timeS)),
      tl.on("view", () => this._scheduleViewSave()),
      tl.on("selection", () => {
        this._updateToolbar();
        this.chairPanel.updateRange();
      }),
      tl.on("selection-input", () => this._updateToolbar()),
    );
    const onKey = (/** @type {KeyboardEvent} */ e) => this._onKey(e);
    document.addEventListener("keydown", onKey);
    this.cleanups.push(() => document.removeEventListener("keydown", onKey));
  }

  // ---------------------------------------------------------------- loading
  _attachMedia() {
    if (this.video.getAttribute("src")) return;
    this.video.src = this.api.mediaUrl(this.projectId);
  }

  /**
   * Load the composed timeline and draw it. The first load of the editor leaves the fan grid out
   * (FIRST_BLOCKS) so the lanes are drawn sooner, and fetches it right after; later loads (after
   * an edit) take every block. The editor is "ready" once the fan grid is in too.
   */
  async reloadTimeline() {
    const seq = (this._loadSeq = (this._loadSeq || 0) + 1);
    const first = this._firstLoads && this._firstLoads.bin;
    if (this._firstLoads) this._firstLoads.bin = null;
    const firstOpen = this.data === null;
    let buf;
    try {
      if (first) {
        const got = await first;
        if ("error" in got) throw got.error;
        buf = got.value;
      } else {
        buf = await this.api.timelineBin(this.projectId, "composed", firstOpen ? FIRST_BLOCKS : null);
      }
    } catch (err) {
      this._attachMedia();
      if (err instanceof ApiError && err.status === 404 && this.project && !this.project.has_timeline) return;
      this._showNotice(`Could not load the timeline: ${errorText(err)}`);
      return;
    }
    if (Number.isNaN(this.timing.binFetched)) this.timing.binFetched = performance.now() - this.timing.start;
    if (this.disposed || seq !== this._loadSeq) return; // a newer load is under way
    let data;
    try {
      data = TimelineData.fromBuffer(buf);
    } catch (err) {
      this._showNotice(`The timeline could not be read: ${errorText(err)}`);
      return;
    }
    this.data = data;
    if (Number.isNaN(this.timing.dataLoaded)) this.timing.dataLoaded = performance.now() - this.timing.start;
    this.chair.temperature = this.tempRange();
    this.detailLane.clearStroke();
    this.temperatureLane.clearStroke();
    this.timeline.invalidate();
    this.lastTick = -1;
    this._onTime(this.player.currentTime, this.player.playing);
    this._updateToolbar();
    // Runs after the lanes' redraw in the same frame: this revision is now on screen.
    this.loop.request("drawn", () => {
      if (data.hasFans) this.drawnRevision = data.revision;
      this._attachMedia();
      if (Number.isNaN(this.timing.firstRender)) this.timing.firstRender = performance.now() - this.timing.start;
      if (data.hasFans) this.host.dataset.ready = "true";
    });
    if (!data.hasFans) await this._loadFans(seq);
  }

  /**
   * The fan grid after a load without it; a timeline that moved on meanwhile is loaded whole.
   * @param {number} seq the load it completes
   */
  async _loadFans(seq) {
    let buf;
    try {
      buf = await this.api.timelineBin(this.projectId, "composed", "fans");
    } catch (err) {
      if (!this.disposed && seq === this._loadSeq) this._showNotice(`Could not load the fan grid: ${errorText(err)}`);
      return;
    }
    if (this.disposed || seq !== this._loadSeq || !this.data) return;
    let data;
    try {
      data = this.data.withFans(buf);
    } catch (err) {
      await this.reloadTimeline(); // another revision meanwhile: take every block of the current one
      return;
    }
    this.data = data;
    this.lastTick = -1;
    this._onTime(this.player.currentTime, this.player.playing);
    this.loop.request("fans-in", () => {
      this.drawnRevision = data.revision;
      this.host.dataset.ready = "true";
    });
  }

  async _loadEdits() {
    const got = await this._firstLoads.edits;
    if ("error" in got) {
      this._showNotice(`Could not load the edit history: ${errorText(got.error)}`);
      return;
    }
    this.session = new EditSession(this.api, this.projectId, got.value);
    const s = this.session;
    this.cleanups.push(
      s.on("changed", ({ reason }) => {
        this._updateHistoryButtons();
        this._refreshMarkers();
        if (reason !== "params") this.reloadTimeline();
      }),
      s.on("save", ({ state, message }) => {
        this.saveEl.textContent = message;
        this.saveEl.dataset.state = state;
        if (state === "error") toast(message, "error");
      }),
      s.on("conflict", ({ message }) => {
        toast(message, "warn", 10000);
        this._showNotice(message);
      }),
    );
    this.saveEl.textContent = "All changes saved";
    this.saveEl.dataset.state = "saved";
    this._refreshMarkers();
    this._updateHistoryButtons();
  }

  /** @param {import("../../data/api.js").Project} project */
  async _loadWaveform(project) {
    const n = project.n_ticks || Math.ceil((project.duration_s || 0) / this.tickS);
    const points = Math.max(1000, Math.min(60000, n * 4));
    try {
      const wf = await this.api.waveform(this.projectId, points);
      if (this.disposed) return;
      if (wf.has_audio === false) this.waveformLane.setStatus("No audio stream");
      else this.waveformLane.setPeaks(wf);
    } catch (err) {
      this.waveformLane.setStatus(`Waveform unavailable: ${errorText(err)}`);
    }
    this.timing.waveformLoaded = performance.now() - this.timing.start;
    this.timeline.invalidate("waveform");
  }

  /** @param {import("../../data/api.js").Project} project */
  _setNoTimeline(project) {
    const running = project.job && (project.job.status === "queued" || project.job.status === "running");
    if (!running) {
      this._showNotice(
        project.status === "failed"
          ? `The last generation failed${project.job && project.job.error ? `: ${project.job.error}` : ""}. Use Regenerate to try again.`
          : "This project has no timeline yet. Use Regenerate to generate one.",
      );
    }
    this.thresholdPanel.setDisabled(true);
  }

  _refreshMarkers() {
    if (!this.session) return;
    this.markers = this.session.markers.map((m) => ({ ...m }));
    if (this.selectedMarker && !this.markers.some((m) => m.id === this.selectedMarker)) this.selectedMarker = null;
    this.markersLane.settle();
    this.timeline.invalidate("markers");
    this._updateToolbar();
  }

  // --------------------------------------------------------------- playback
  /** @param {number} timeS @param {boolean} playing */
  _onTime(timeS, playing) {
    this.timeline.setPlayhead(timeS, { page: playing });
    const dur = this.timeline.durationS;
    this.timeEl.textContent = `${formatTime(timeS)} / ${formatTime(dur)}`;
    const tick = this.data ? this.data.tickAt(timeS) : -1;
    if (this.data && tick === this.lastTick) return;
    this.lastTick = tick;
    const v = this.data ? this.data.valuesAt(tick) : null;
    this.chair.update(v, ACTUATOR_IDS);
    this.fanOverlay.update(v ? v.fan_grid : null);
  }

  async togglePlay() {
    try {
      await this.player.toggle();
    } catch (err) {
      toast(`Playback failed: ${errorText(err)}`, "error");
    }
  }

  /** @param {number} timeS */
  seek(timeS) {
    this.player.seek(timeS);
    this.timeline.reveal(this.player.currentTime);
  }

  /** @param {boolean} on */
  setOverlay(on) {
    this.fanOverlay.setVisible(on);
    this.overlayBtn.setAttribute("aria-pressed", String(on));
    this.lastTick = -1;
    this._onTime(this.player.currentTime, this.player.playing);
    this._scheduleViewSave();
  }

  /** @param {boolean} on */
  setFollow(on) {
    this.timeline.follow = on;
    this.followBtn.setAttribute("aria-pressed", String(on));
    this._scheduleViewSave();
  }

  // ------------------------------------------------------------ view state
  /** @param {Record<string, any>} view */
  _restoreView(view) {
    this._restoringView = true;
    const tl = this.timeline;
    if (Array.isArray(view.hidden_lanes)) {
      for (const id of view.hidden_lanes) {
        tl.setLaneVisible(id, false);
        const cb = /** @type {HTMLInputElement|null} */ (this.lanesMenu.querySelector(`[data-testid="lane-toggle-${id}"]`));
        if (cb) cb.checked = false;
      }
    }
    if (typeof view.detail_actuator === "string") this.detailLane.setActuator(view.detail_actuator);
    if (view.fan_overlay) this.setOverlay(true);
    if (view.follow === false) this.setFollow(false);
    if (typeof view.px_per_s === "number") {
      // The width is known after the first layout; restore then.
      requestAnimationFrame(() => {
        tl.restoreView({ pxPerS: view.px_per_s, startS: view.start_s });
        this._restoringView = false;
      });
    } else {
      this._restoringView = false;
    }
  }

  _scheduleViewSave() {
    if (this._restoringView || !this.timeline) return;
    if (this._viewTimer) clearTimeout(this._viewTimer);
    this._viewTimer = setTimeout(() => this._saveView(), VIEW_SAVE_DELAY_MS);
  }

  async _saveView() {
    this._viewTimer = null;
    const tl = this.timeline;
    const view = {
      px_per_s: Math.round(tl.pxPerS * 1000) / 1000,
      start_s: Math.round(tl.startS * 1000) / 1000,
      hidden_lanes: tl.lanes.filter((l) => l.row.hidden).map((l) => l.lane.id),
      fan_overlay: this.fanOverlay.visible,
      follow: tl.follow,
      detail_actuator: this.detailLane.actuator,
    };
    try {
      await this.api.patchProject(this.projectId, { view });
    } catch (err) {
      if (!this.disposed) toast(`The view settings were not saved: ${errorText(err)}`, "warn");
    }
  }

  // ---------------------------------------------------------------- editing
  /** @param {"select"|"pencil"|"points"} tool */
  setTool(tool) {
    this.timeline.tool = tool;
    if (tool !== "points" && this.points.length) this.setPoints([]);
    this._updateToolbar();
  }

  /** @param {string} lane */
  toggleLane(lane) {
    const tl = this.timeline;
    const sel = tl.selection;
    const current = sel ? sel.lanes : tl.defaultLanes;
    const next = current.includes(lane) ? current.filter((l) => l !== lane) : [...current, lane];
    if (!next.length) return;
    if (sel) tl.setSelection({ ...sel, lanes: next });
    else tl.defaultLanes = next;
    this._updateToolbar();
  }

  /** @param {(sel: import("../../core/timeline.js").Selection) => Record<string, any>} build */
  _selectionOp(build) {
    const sel = this.timeline.selection;
    if (!sel) {
      toast("Select a range first (drag on the lanes).", "warn");
      return Promise.resolve(false);
    }
    let op;
    try {
      op = build(sel);
    } catch (err) {
      toast(errorText(err), "warn");
      return Promise.resolve(false);
    }
    return this.submit(op);
  }

  /**
   * Save one op (autosave); the composed timeline is reloaded when the server accepted it.
   * @param {Record<string, any>} op
   */
  submit(op) {
    if (!this.session || !this.data) {
      toast("There is no timeline to edit yet.", "warn");
      return Promise.resolve(false);
    }
    return this.session.submit(op);
  }

  /**
   * @param {Record<string, any>} op
   * @param {{clearStroke: () => void}} lane
   */
  async _submitStroke(op, lane) {
    const ok = await this.submit(op);
    if (!ok) {
      lane.clearStroke();
      this.timeline.invalidate();
    }
  }

  /** @param {File} file */
  async importTimeline(file) {
    if (!this.session || !this.data) {
      toast("Generate a timeline before importing one over it.", "warn");
      return;
    }
    if (await this.session.importFile(file)) toast(`Imported ${file.name}; Undo brings the previous tracks back.`);
  }

  async undo() {
    if (this.session) await this.session.undo();
  }

  async redo() {
    if (this.session) await this.session.redo();
  }

  copy() {
    const sel = this.timeline.selection;
    if (!sel || !this.data) return;
    let c;
    try {
      c = this.clipboard.copy(this.data, sel);
    } catch (err) {
      toast(errorText(err), "warn");
      return;
    }
    toast(`Copied ${c.length} ticks of ${sel.lanes.join(", ")}.`);
    this._updateToolbar();
  }

  paste() {
    if (!this.clipboard.content) return Promise.resolve(false);
    if (!this.data) return Promise.resolve(false);
    return this.submit(this.clipboard.pasteOp(this.data.tickAt(this.player.currentTime)));
  }

  /** @param {Array<[number, number]>} points */
  setPoints(points) {
    this.points = points;
    this.temperatureLane.setPoints(points);
    this.timeline.invalidate("temperature");
    this._updateToolbar();
  }

  async applyPoints() {
    let op;
    try {
      op = tempPointsOp(this.points);
    } catch (err) {
      toast(errorText(err), "warn");
      return;
    }
    if (await this.submit(op)) this.setPoints([]);
  }

  // ---------------------------------------------------------------- markers
  /** @param {string|null} id */
  selectMarker(id) {
    this.selectedMarker = id;
    this.timeline.invalidate("markers");
    this._updateToolbar();
  }

  /** @param {number} timeS */
  async addMarker(timeS) {
    const label = await promptDialog({ title: "Add a marker", label: `Label at ${formatTime(timeS)}`, value: `Marker ${this.markers.length + 1}`, ok: "Add" });
    if (label === null) return;
    const op = markerAddOp(Math.round(timeS * 1000) / 1000, label);
    if (await this.submit(op)) this.selectMarker(op.marker.id);
  }

  /** @param {string} id @param {number} t_s */
  async moveMarker(id, t_s) {
    const ok = await this.submit(markerUpdateOp(id, { t_s }));
    if (!ok) {
      this.markersLane.settle();
      this.timeline.invalidate("markers");
    }
  }

  /** @param {string} id */
  async renameMarker(id) {
    const m = this.markers.find((x) => x.id === id);
    if (!m) return;
    const label = await promptDialog({ title: "Rename the marker", label: "Label", value: m.label, ok: "Rename" });
    if (label === null || label === m.label) return;
    await this.submit(markerUpdateOp(id, { label }));
  }

  /** @param {string} id */
  async deleteMarker(id) {
    const m = this.markers.find((x) => x.id === id);
    if (!m) return;
    if (await this.submit(markerDeleteOp(id))) this.selectMarker(null);
  }

  // ------------------------------------------------------------- thresholds
  /** @param {string} name @param {number} value live value while dragging */
  _thresholdInput(name, value) {
    const lane = this.featureLanes.find((l) => l.name === name);
    if (lane) {
      lane.draft = value;
      this.timeline.invalidate(lane.id);
    }
    this.thresholdPanel.set(name, value);
  }

  /** A threshold drag was cancelled: show the committed value again. @param {string} name */
  _thresholdCancel(name) {
    const lane = this.featureLanes.find((l) => l.name === name);
    if (lane) {
      lane.draft = null;
      this.timeline.invalidate(lane.id);
    }
    if (name in this.thresholds) this.thresholdPanel.set(name, this.thresholds[name]);
  }

  /**
   * Commit a threshold: the server re-derives the vibration from its cached analysis (or starts
   * an analysis job when that is needed), then the timeline is reloaded.
   * @param {string} name
   * @param {number} value
   */
  async commitThreshold(name, value) {
    const lane = this.featureLanes.find((l) => l.name === name);
    if (lane) lane.draft = null;
    const before = this.thresholds[name];
    this.thresholds = { ...this.thresholds, [name]: value };
    this.thresholdPanel.set(name, value);
    this.timeline.invalidate();
    if (!this.session || value === before) return;
    const thresholds = { ...this.thresholds };
    /** @type {import("../../data/api.js").Job|null} */
    let job = null;
    let derived = false;
    const ok = await this.session.run(async () => {
      const res = await this.api.putParams(this.projectId, { thresholds });
      if (res.job) job = res.job;
      if (res.derived && typeof res.revision === "number") {
        derived = true;
        this.session?.setRevision(res.revision);
      }
    });
    if (!ok) {
      this.thresholds = { ...this.thresholds, [name]: before };
      this.thresholdPanel.set(name, before);
      this.timeline.invalidate();
      return;
    }
    if (derived) {
      // Derived from the cache: shown now. A job that came with it refines the ticks the cache could
      // only estimate, in the background (docs/API.md "Parameters").
      await this.reloadTimeline();
      this._updateParamsInfo();
      if (job) await this._followJob(job);
      return;
    }
    if (job) await this._followJob(job);
    this._updateParamsInfo();
  }

  // ------------------------------------------------------------ regenerate
  async regenerate() {
    const cfg = this.config;
    const p = (this.project && this.project.params) || {};
    const params = await regenerateDialog({
      presets: cfg.presets || ["balanced"],
      modes: cfg.modes || ["audio"],
      preset: p.preset || cfg.default_preset || "balanced",
      mode: p.mode || (cfg.modes && cfg.modes[0]) || "audio",
      thresholds: { ...this.thresholds },
    });
    if (!params) return;
    let res;
    try {
      res = await this.api.generate(this.projectId, params);
    } catch (err) {
      toast(`Could not start the generation: ${errorText(err)}`, "error");
      return;
    }
    await this._followJob(res.job);
  }

  /** @param {import("../../data/api.js").Job} job */
  async _followJob(job) {
    this.jobsFollowed += 1;
    try {
      await this._followJobInner(job);
    } finally {
      this.jobsFollowed -= 1;
    }
  }

  /** @param {import("../../data/api.js").Job} job */
  async _followJobInner(job) {
    if (this.jobProgress) this.jobProgress.close();
    const progress = new JobProgress(this.api);
    this.jobProgress = progress;
    this.jobSlot.replaceChildren(progress.el);
    this.jobSlot.hidden = false;
    this.regenBtn.disabled = true;
    this.thresholdPanel.setDisabled(true);
    let final;
    try {
      final = await progress.follow(job);
    } catch (err) {
      this.regenBtn.disabled = false;
      return;
    }
    if (this.disposed) return;
    this.regenBtn.disabled = false;
    try {
      this.project = await this.api.project(this.projectId);
    } catch (err) {
      toast(`Could not reload the project: ${errorText(err)}`, "error");
      return;
    }
    if (this.project.params && this.project.params.thresholds) this.thresholds = { ...this.project.params.thresholds };
    for (const [n, v] of Object.entries(this.thresholds)) this.thresholdPanel.set(n, v);
    this._updateParamsInfo();
    if (final.status === "done") {
      this._hideNotice();
      this.thresholdPanel.setDisabled(false);
      if (this.session) await this.session.reload();
      else await this.reloadTimeline();
      setTimeout(() => {
        if (this.jobProgress === progress) this.jobSlot.hidden = true;
      }, 2500);
    } else {
      this.thresholdPanel.setDisabled(!this.project.has_timeline);
      if (final.status === "failed") toast(`Generation failed: ${final.error || "unknown error"}`, "error", 10000);
    }
  }

  // -------------------------------------------------------------- keyboard
  /** @param {KeyboardEvent} e */
  _onKey(e) {
    if (this.disposed || document.querySelector("dialog[open]")) return;
    const t = /** @type {HTMLElement} */ (e.target);
    const tag = t && t.tagName;
    const inputType = tag === "INPUT" ? /** @type {HTMLInputElement} */ (t).type : "";
    // Text fields keep every key (their own undo included); sliders keep their arrow keys.
    if (t && (t.isContentEditable || tag === "TEXTAREA" || tag === "SELECT" || (tag === "INPUT" && !["range", "checkbox", "button"].includes(inputType)))) return;
    if (inputType === "range" && /^(Arrow|Home|End|Page)/.test(e.key)) return;
    const mod = e.ctrlKey || e.metaKey;
    const tl = this.timeline;
    const tick = this.tickS;
    let handled = true;
    if (mod && (e.key === "z" || e.key === "Z")) {
      if (e.shiftKey) this.redo();
      else this.undo();
    } else if (mod && e.key === "y") {
      this.redo();
    } else if (mod && e.key === "c") {
      this.copy();
    } else if (mod && e.key === "v") {
      this.paste();
    } else if (mod) {
      handled = false;
    } else if (e.key === " ") {
      this.togglePlay();
    } else if (e.key === "ArrowLeft" || e.key === "ArrowRight") {
      const step = e.shiftKey ? 1 : tick;
      const dir = e.key === "ArrowLeft" ? -1 : 1;
      const base = Math.round(this.player.currentTime / tick) * tick;
      this.seek(base + dir * step);
    } else if (e.key === "Home") {
      this.seek(0);
    } else if (e.key === "End") {
      this.seek(tl.durationS);
    } else if (e.key === "+" || e.key === "=") {
      tl.zoomBy(ZOOM_STEP);
    } else if (e.key === "-" || e.key === "_") {
      tl.zoomBy(1 / ZOOM_STEP);
    } else if (e.key === "0") {
      tl.fit();
    } else if (e.key === "Delete" || e.key === "Backspace") {
      if (this.selectedMarker) this.deleteMarker(this.selectedMarker);
      else if (tl.selection) this._selectionOp((sel) => clearOp(sel));
      else handled = false;
    } else if (e.key === "Escape") {
      if (this.points.length) this.setPoints([]);
      else if (tl.selection) tl.setSelection(null);
      else if (this.selectedMarker) this.selectMarker(null);
      else handled = false;
    } else {
      handled = false;
    }
    if (handled) e.preventDefault();
  }

  // ------------------------------------------------------------------- UI
  _updateToolbar() {
    const tl = this.timeline;
    if (!tl) return;
    const sel = tl.selection;
    this.toolbar.update({
      tool: tl.tool,
      selection: sel,
      lanes: sel ? sel.lanes : tl.defaultLanes,
      tickS: this.tickS,
      canPaste: !!this.clipboard.content,
      points: this.points.length,
      markerSelected: !!this.selectedMarker,
      ready: !!this.data,
    });
  }

  _updateHistoryButtons() {
    const s = this.session;
    this.undoBtn.disabled = !s || !s.canUndo;
    this.redoBtn.disabled = !s || !s.canRedo;
    if (s) {
      this.host.dataset.revision = String(s.revision);
      this.host.dataset.cursor = String(s.cursor);
    }
  }

  _updateParamsInfo() {
    const p = this.project && this.project.params;
    if (!p) return;
    this.paramsInfo.textContent = `Preset ${p.preset} · mode ${p.mode}`;
  }

  /** @param {string} text */
  _showNotice(text) {
    this.notice.textContent = text;
    this.notice.hidden = false;
  }

  _hideNotice() {
    this.notice.hidden = true;
  }

  /** @param {string} text */
  _fatal(text) {
    this.main.replaceChildren(h("div", { class: "empty", role: "alert", "data-testid": "editor-error" }, text, " ", h("a", { href: "#/" }, "Back to the projects")));
  }

  // ---------------------------------------------------------------- debug
  /** A read-only snapshot for tests and the benchmark (window.autohaptics). */
  debugState() {
    const tl = this.timeline;
    return {
      projectId: this.projectId,
      revision: this.session ? this.session.revision : null,
      cursor: this.session ? this.session.cursor : null,
      nOps: this.session ? this.session.nOps : null,
      ready: !!this.data,
      dataRevision: this.data ? this.data.revision : null,
      drawnRevision: this.drawnRevision ?? null,
      nTicks: this.data ? this.data.nTicks : null,
      playing: this.player ? this.player.playing : false,
      currentTime: this.player ? this.player.currentTime : 0,
      playheadS: tl ? tl.playheadS : 0,
      pxPerS: tl ? tl.pxPerS : null,
      startS: tl ? tl.startS : null,
      visibleS: tl ? tl.visibleS : null,
      durationS: tl ? tl.durationS : null,
      selection: tl && tl.selection ? { ...tl.selection, lanes: [...tl.selection.lanes] } : null,
      tool: tl ? tl.tool : null,
      thresholds: { ...this.thresholds },
      markers: this.markers.map((m) => ({ ...m })),
      timing: { ...this.timing },
      waveformReady: !Number.isNaN(this.timing.waveformLoaded),
      saveState: this.saveEl ? this.saveEl.dataset.state || "" : "",
      jobActive: this.jobsFollowed > 0,
      chair: this.chairPanel && this.chairPanel.status
        ? { active: this.chairPanel.active, state: this.chairPanel.status.state, reporting: this.chairSync.active }
        : null,
    };
  }

  /** Values of the composed timeline at one tick (a copy). @param {number} tick */
  valuesAt(tick) {
    if (!this.data) return null;
    const v = this.data.valuesAt(tick);
    return { vibration: v.vibration, temperature_c: v.temperature_c, fans: v.fans, fan_grid: Array.from(v.fan_grid), features: v.features };
  }

  /** Page rectangle (client px) of a lane's canvas, for tests that point at lanes. @param {string} id */
  laneRect(id) {
    const e = this.timeline && this.timeline.laneEntry(id);
    if (!e) return null;
    const r = e.canvas.getBoundingClientRect();
    return { x: r.x, y: r.y, width: r.width, height: r.height };
  }

  /** Client x of a time on the timeline. @param {number} timeS */
  clientXOf(timeS) {
    const r = this.timeline.rulerCanvas.getBoundingClientRect();
    return r.x + this.timeline.timeToX(timeS);
  }

  destroy() {
    this.disposed = true;
    if (this._viewTimer) {
      clearTimeout(this._viewTimer);
      this._saveView();
    }
    for (const fn of this.cleanups) fn();
    if (this.jobProgress) this.jobProgress.close();
    if (this.player) this.player.destroy();
    if (this.fanOverlay) this.fanOverlay.destroy();
    if (this.timeline) this.timeline.destroy();
  }
}
