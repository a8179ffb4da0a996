/**
 * The editor screen: the video with the fan-grid overlay and the chair diagram beside a
 * multi-lane timeline sharing one playhead, the editing toolbar, thresholds, regenerate and
 * export. The shell builds the screen from its parts (this folder) and holds what they share;
 * the parts reach each other through it. It owns the three kinds of state:
 *
 * - edits (saved and undoable): the server's op list, through EditSession (./edits.js);
 * - view settings (saved, not undoable): zoom, scroll, hidden lanes, overlay toggle (./view.js);
 * - playback position and connection status (neither): the player (./media.js) and the chair (./chair.js).
 */

import { h } from "../../core/dom.js";
import { FrameLoop } from "../../core/frameloop.js";
import { TimelineView } from "../../core/timeline.js";
import { ApiError, errorText } from "../../data/http.js";
import { drawnTemperatureRange } from "../../data/layout.js";
import { closeMenusOutside } from "../../panels/menus.js";
import { EditorChair } from "./chair.js";
import { EditActions } from "./edits.js";
import { EditorHeader } from "./header.js";
import { JobFollower } from "./jobs.js";
import { onEditorKey } from "./keys.js";
import { LaneText } from "./lane-text.js";
import { EditorLanes } from "./lanes.js";
import { TimelineLoader, startEditorLoads } from "./loading.js";
import { MarkerActions } from "./markers.js";
import { EditorMedia } from "./media.js";
import { ParamsControl } from "./params.js";
import { ShotActions } from "./shots.js";
import { ViewSettings } from "./view.js";

/**
 * @typedef {{
 *   config: Record<string, any>,
 *   layout: import("../../data/layout.js").ChairLayout,
 *   api: import("../../data/api.js").Api,
 * }} EditorContext
 */

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
    this.layout = ctx.layout;
    this.projectId = projectId;
    this.loop = new FrameLoop();
    // What is open, each null until it is loaded or built.
    this.project = /** @type {import("../../data/api.js").Project|null} */ (null);
    this.data = /** @type {import("../../data/timeline-data.js").TimelineData|null} */ (null);
    this.session = /** @type {import("../../data/edit-session.js").EditSession|null} */ (null);
    this.timeline = /** @type {TimelineView|null} */ (null);
    /** what the chair plays of the temperature track (null until loaded) */
    this.played = /** @type {import("../../data/played-temperature.js").PlayedTemperature|null} */ (null);
    /** revision of the timeline last drawn on the lanes */
    this.drawnRevision = /** @type {number|null} */ (null);
    this.disposed = false;
    /** @type {Array<() => void>} */
    this.cleanups = [];
    /** Milliseconds from `start` (performance.now() when the editor began opening) to each step. */
    this.timing = { start: performance.now(), projectLoaded: NaN, binFetched: NaN, dataLoaded: NaN, firstRender: NaN, waveformLoaded: NaN };
    this.header = new EditorHeader(this);
    this.loader = new TimelineLoader(this);
    this.media = new EditorMedia(this);
    this.chair = new EditorChair(this);
    this.params = new ParamsControl(this);
    this.jobs = new JobFollower(this);
    this.lanes = new EditorLanes(this);
    this.laneText = new LaneText(this);
    this.edits = new EditActions(this);
    this.markers = new MarkerActions(this);
    this.shots = new ShotActions(this);
    this.view = new ViewSettings(this);
  }

  /**
   * @param {import("./loading.js").EditorLoads} [loads] the first requests, when the caller started them already
   */
  async open(loads = startEditorLoads(this.api, this.projectId)) {
    this.loader.first = loads;
    this.main = this.header.build();
    this.chair.stopOnEscape();
    const got = await loads.project;
    if ("error" in got) {
      const err = got.error;
      this.fatal(err instanceof ApiError && err.status === 404 ? "This project does not exist (it may have been deleted)." : errorText(err));
      return;
    }
    const project = got.value;
    this.project = project;
    this.timing.projectLoaded = performance.now() - this.timing.start;
    this.header.nameEl.textContent = project.name;
    document.title = `${project.name} · autohaptics`;
    this.params.takeThresholds(project);
    const durationS = project.duration_s || (project.n_ticks || 1) * this.tickS;
    this._buildWorkspace(durationS);
    this.view.restore(project.view || {});
    const tasks = [this.loader.loadEdits(), this.loader.loadWaveform(project)];
    if (project.has_timeline) {
      tasks.push(this.loader.reload());
    } else {
      loads.bin = null; // a 404 now; the timeline is fetched when a job makes one
      this.loader.showNoTimeline(project);
      this.media.attach();
    }
    await Promise.all(tasks);
    if (project.job && (project.job.status === "queued" || project.job.status === "running")) this.jobs.follow(project.job);
  }

  get tickS() {
    return this.layout.tickS;
  }

  /** Temperature range for drawing: the generator's range, widened to the data and to what the chair plays. */
  tempRange() {
    return drawnTemperatureRange(this.layout.temperature, this.data, this.played);
  }

  /** @param {number} durationS */
  _buildWorkspace(durationS) {
    const features = this.layout.features;
    const videoWrap = this.media.buildVideo(durationS);
    const side = h("aside", { class: "side" }, this.params.build(features), this.params.info, this.chair.buildPanel());
    const stage = h("section", { class: "stage" }, videoWrap, this.chair.buildDiagram(), side, this.shots.panel.build());
    this.shots.panel.onToggle = (open) => {
      stage.classList.toggle("shots-open", open);
      this.view.scheduleSave();
    };
    this.notice = h("div", { class: "notice", hidden: true, role: "status", "data-testid": "editor-notice" });
    this.timelineHost = h("div", { class: "timeline-host" });
    const toolbar = this.edits.buildToolbar();
    const transport = this.media.buildTransport(durationS);
    transport.append(this.edits.toolbar.markersEl, this.edits.toolbar.pointsGroup, this.edits.toolbar.info);
    this.main.append(stage, this.jobs.build(), this.notice, transport, toolbar, this.timelineHost);
    this.timeline = new TimelineView(this.timelineHost, { durationS, tickS: this.tickS, frameLoop: this.loop, defaultLanes: this.layout.actuatorIds });
    this.lanes.add(this.timeline, features);
    this.laneText.attach(this.timeline);
    this._wireEvents();
    this.edits.updateToolbar();
    this.params.updateInfo();
    this.chair.panel.open();
  }

  _wireEvents() {
    const tl = this.timeline;
    const player = this.media.player;
    this.cleanups.push(
      ...this.media.wire(),
      tl.on("scrub", ({ timeS }) => player.seek(timeS)),
      tl.on("seek", ({ timeS }) => player.seek(timeS)),
      tl.on("view", () => this.view.scheduleSave()),
      tl.on("selection", () => {
        this.edits.updateToolbar();
        this.chair.panel.updateRange();
        this.shots.panel.refresh();
      }),
      tl.on("selection-input", () => this.edits.updateToolbar()),
      closeMenusOutside(),
    );
    const onKey = (/** @type {KeyboardEvent} */ e) => onEditorKey(this, e);
    document.addEventListener("keydown", onKey);
    this.cleanups.push(() => document.removeEventListener("keydown", onKey));
  }

  /** @param {string} text */
  showNotice(text) {
    this.notice.textContent = text;
    this.notice.hidden = false;
  }

  hideNotice() {
    this.notice.hidden = true;
  }

  /** @param {string} text */
  fatal(text) {
    this.main.replaceChildren(h("div", { class: "empty", role: "alert", "data-testid": "editor-error" }, text, " ", h("a", { href: "#/" }, "Back to the projects")));
  }

  destroy() {
    this.disposed = true;
    this.view.flush();
    for (const fn of this.cleanups) fn();
    this.jobs.close();
    this.media.destroy();
    this.shots.destroy();
    if (this.timeline) this.timeline.destroy();
  }
}
