/**
 * What the editor loads: the first requests (all at once, or taken over from index.html), the
 * composed timeline (the fan grid after the rest on the first load), the edit list with its
 * session, and the waveform.
 */

import { ApiError, errorText } from "../../data/http.js";
import { EditSession } from "../../data/edit-session.js";
import { PlayedTemperature } from "../../data/played-temperature.js";
import { FIRST_BLOCKS, TimelineData } from "../../data/timeline-data.js";
import { toast } from "../../panels/widgets.js";

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

export class TimelineLoader {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {EditorLoads|null} the first requests; `bin` is taken by the first load */
    this.first = null;
    /** number of the latest load: an older one that finishes later is dropped */
    this.seq = 0;
  }

  /**
   * Load the composed timeline and draw it. The first load of the editor leaves the fan grid out
   * (FIRST_BLOCKS) so the lanes are drawn sooner, and fetches it right after; later loads (after
   * an edit or a parameter change) take the blocks that changed since the revision on screen
   * (`?since=`). The editor is "ready" once the fan grid is in too.
   */
  async reload() {
    const page = this.page;
    const seq = ++this.seq;
    const held = page.data; // the revision on screen: the answer holds only what changed since it
    let buf;
    try {
      buf = await this._fetch(held);
    } catch (err) {
      page.media.attach();
      if (err instanceof ApiError && err.status === 404 && page.project && !page.project.has_timeline) return;
      page.showNotice(`Could not load the timeline: ${errorText(err)}`);
      return;
    }
    if (Number.isNaN(page.timing.binFetched)) page.timing.binFetched = performance.now() - page.timing.start;
    if (page.disposed || seq !== this.seq) return; // a newer load is under way
    let data;
    try {
      data = TimelineData.fromBuffer(buf, page.layout, held);
    } catch (err) {
      page.showNotice(`The timeline could not be read: ${errorText(err)}`);
      return;
    }
    this._show(data);
    // Runs after the lanes' redraw in the same frame: this revision is now on screen.
    page.loop.request("drawn", () => {
      if (data.hasFans) page.drawnRevision = data.revision;
      page.media.attach();
      if (Number.isNaN(page.timing.firstRender)) page.timing.firstRender = performance.now() - page.timing.start;
      if (data.hasFans) page.host.dataset.ready = "true";
      page.shots.load(data.revision);
    });
    if (!data.hasFans) await this._loadFans(seq);
  }

  /**
   * The binary timeline: the first request's answer once, then the blocks changed since `held`.
   * @param {TimelineData|null} held
   */
  async _fetch(held) {
    const page = this.page;
    const first = this.first && this.first.bin;
    if (this.first) this.first.bin = null;
    if (!first) {
      return page.api.timelineBin(page.projectId, "composed", held === null ? FIRST_BLOCKS : null,
        held === null ? null : held.revision);
    }
    const got = await first;
    if ("error" in got) throw got.error;
    return got.value;
  }

  /** Put a new timeline on screen. @param {TimelineData} data */
  _show(data) {
    const page = this.page;
    page.data = data;
    if (Number.isNaN(page.timing.dataLoaded)) page.timing.dataLoaded = performance.now() - page.timing.start;
    page.chair.diagram.temperature = page.tempRange();
    page.lanes.detail.clearStroke();
    page.lanes.temperature.clearStroke();
    page.timeline.invalidate();
    page.media.refresh();
    page.edits.updateToolbar();
    page.params.showShare(data);
    this.loadPlayed(data.revision);
  }

  /**
   * The temperature the chair plays for a revision on screen; dropped when another one replaced it.
   * @param {number} revision
   */
  async loadPlayed(revision) {
    const page = this.page;
    let played;
    try {
      played = new PlayedTemperature(await page.api.chairTemperature(page.projectId));
    } catch (err) {
      if (!page.disposed) toast(`Could not load the chair's temperature curve: ${errorText(err)}`, "warn");
      return;
    }
    if (page.disposed || !page.data || page.data.revision !== revision || played.revision !== revision) return;
    page.played = played;
    page.timeline.invalidate("temperature");
    page.laneText.refresh();
  }

  /**
   * The fan grid after a load without it; a timeline that moved on meanwhile is loaded whole.
   * @param {number} seq the load it completes
   */
  async _loadFans(seq) {
    const page = this.page;
    let buf;
    try {
      buf = await page.api.timelineBin(page.projectId, "composed", "fans");
    } catch (err) {
      if (!page.disposed && seq === this.seq) page.showNotice(`Could not load the fan grid: ${errorText(err)}`);
      return;
    }
    if (page.disposed || seq !== this.seq || !page.data) return;
    let data;
    try {
      data = page.data.withFans(buf);
    } catch (err) {
      await this.reload(); // another revision meanwhile: take every block of the current one
      return;
    }
    page.data = data;
    page.media.refresh();
    page.loop.request("fans-in", () => {
      page.drawnRevision = data.revision;
      page.host.dataset.ready = "true";
    });
  }

  /** The edit list from the first requests, and the session that edits it. */
  async loadEdits() {
    const page = this.page;
    const got = await this.first.edits;
    if ("error" in got) {
      page.showNotice(`Could not load the edit history: ${errorText(got.error)}`);
      return;
    }
    const s = new EditSession(page.api, page.projectId, got.value);
    page.session = s;
    page.cleanups.push(
      s.on("changed", ({ reason, params, job }) => {
        page.header.updateHistory();
        page.markers.refresh();
        if (params) page.params.restored(params, job || null);  // undo / redo of a parameter change
        if (reason !== "params") this.reload();
      }),
      s.on("save", ({ state, message }) => {
        page.header.showSave(state, message);
        if (state === "error") toast(message, "error");
      }),
      s.on("conflict", ({ message }) => {
        toast(message, "warn", 10000);
        page.showNotice(message);
      }),
    );
    page.header.showSave("saved", "All changes saved");
    page.markers.refresh();
    page.header.updateHistory();
  }

  /** @param {import("../../data/api.js").Project} project */
  async loadWaveform(project) {
    const page = this.page;
    const n = project.n_ticks || Math.ceil((project.duration_s || 0) / page.tickS);
    const points = Math.max(1000, Math.min(60000, n * 4));
    const lane = page.lanes.waveform;
    try {
      const wf = await page.api.waveform(page.projectId, points);
      if (page.disposed) return;
      if (wf.has_audio === false) lane.setStatus("No audio stream");
      else lane.setPeaks(wf);
    } catch (err) {
      lane.setStatus(`Waveform unavailable: ${errorText(err)}`);
    }
    page.timing.waveformLoaded = performance.now() - page.timing.start;
    page.timeline.invalidate("waveform");
  }

  /** A project without a timeline says why, and its thresholds wait for one. @param {import("../../data/api.js").Project} project */
  showNoTimeline(project) {
    const running = project.job && (project.job.status === "queued" || project.job.status === "running");
    if (!running) {
      this.page.showNotice(
        project.status === "failed"
          ? `The last generation failed${project.job && project.job.error ? `: ${project.job.error}` : ""}. Use Regenerate to try again.`
          : "This project has no timeline yet. Use Regenerate to generate one.",
      );
    }
    this.page.params.panel.setDisabled(true);
  }
}
