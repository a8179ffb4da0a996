/**
 * The generation parameters in the editor: the thresholds (sliders and the lines on the feature
 * lanes, live while dragged, committed on release), the density (the `intensity.density`
 * override) with the share of the film that vibrates, the preset and mode line, and Regenerate.
 */

import { h } from "../../core/dom.js";
import { errorText } from "../../data/http.js";
import { regenerateDialog } from "../../panels/regenerate.js";
import { ThresholdsPanel } from "../../panels/thresholds.js";
import { toast } from "../../panels/widgets.js";

const DENSITY = "intensity.density";

export class ParamsControl {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {Record<string, number>} */
    this.thresholds = { ...(page.config.default_thresholds || {}) };
    /** @type {Record<string, unknown>} the project's dotted overrides (the density is one) */
    this.overrides = {};
    /** @type {ThresholdsPanel|null} */
    this.panel = null;
    this.info = h("p", { class: "params-info", "data-testid": "params-info" });
  }

  /** The thresholds panel. @param {string[]} features */
  build(features) {
    this.panel = new ThresholdsPanel(features, {
      onInput: (name, v) => this.input(name, v),
      onCommit: (name, v) => this.commit(name, v),
      onDensity: (share) => this.commitDensity(share),
    });
    this.showThresholds();
    return this.panel.el;
  }

  /** Take the project's thresholds (when it has its own). @param {import("../../data/api.js").Project} project */
  takeThresholds(project) {
    if (project.params && project.params.thresholds) this.thresholds = { ...project.params.thresholds };
    if (project.params && project.params.overrides) this.overrides = { ...project.params.overrides };
  }

  showThresholds() {
    for (const [n, v] of Object.entries(this.thresholds)) this.panel.set(n, v);
    const d = this.overrides[DENSITY];
    this.panel.setDensity(d === undefined || d === null ? null : Number(d));
  }

  /**
   * The share of the film's ticks that vibrate in the timeline on screen (any actuator on).
   * @param {import("../../data/timeline-data.js").TimelineData} data
   */
  showShare(data) {
    if (!this.panel) return;
    const nAct = data.shape.actuatorIds.length;
    let on = 0;
    for (let k = 0; k < data.nTicks; k++) {
      for (let i = 0; i < nAct; i++) {
        if (data.vibration[k * nAct + i] > 0) {
          on++;
          break;
        }
      }
    }
    this.panel.setShare(on / data.nTicks);
  }

  /**
   * Commit the density (a share 0..1, or null to follow the thresholds alone): re-derived like a
   * threshold. @param {number|null} share
   */
  async commitDensity(share) {
    if (!this.page.session) return;
    const before = this.overrides;
    const overrides = { ...before };
    if (share === null) delete overrides[DENSITY];
    else overrides[DENSITY] = share;
    this.overrides = overrides;
    const ok = await this._put({ overrides });
    if (!ok) {
      this.overrides = before;
      this.showThresholds();
    }
  }

  /** @param {string} name */
  _lane(name) {
    return this.page.lanes.features.find((l) => l.name === name);
  }

  /** @param {string} name @param {number} value live value while dragging */
  input(name, value) {
    const lane = this._lane(name);
    if (lane) {
      lane.draft = value;
      this.page.timeline.invalidate(lane.id);
    }
    this.panel.set(name, value);
  }

  /** A threshold drag was cancelled: show the committed value again. @param {string} name */
  cancel(name) {
    const lane = this._lane(name);
    if (lane) {
      lane.draft = null;
      this.page.timeline.invalidate(lane.id);
    }
    if (name in this.thresholds) this.panel.set(name, this.thresholds[name]);
  }

  /**
   * Commit a threshold: the server re-derives the vibration from its cached analysis (or starts
   * an analysis job when that is needed), then the timeline is reloaded.
   * @param {string} name
   * @param {number} value
   */
  async commit(name, value) {
    const page = this.page;
    const lane = this._lane(name);
    if (lane) lane.draft = null;
    const before = this.thresholds[name];
    this.thresholds = { ...this.thresholds, [name]: value };
    this.panel.set(name, value);
    page.timeline.invalidate();
    if (!page.session || value === before) return;
    const ok = await this._put({ thresholds: { ...this.thresholds } });
    if (!ok) {
      this.thresholds = { ...this.thresholds, [name]: before };
      this.panel.set(name, before);
      page.timeline.invalidate();
    }
  }

  /**
   * Send changed parameters: the server re-derives the vibration from its cached analysis (or
   * starts an analysis job when that is needed), then the timeline is reloaded.
   * @param {import("../../data/api.js").Params} body
   * @returns {Promise<boolean>} false when the server refused them
   */
  async _put(body) {
    const page = this.page;
    /** @type {import("../../data/api.js").Job|null} */
    let job = null;
    let derived = false;
    const ok = await page.session.run(async () => {
      const res = await page.api.putParams(page.projectId, body);
      if (res.job) job = res.job;
      derived = Boolean(res.derived);
      // Recorded as an undoable `params` op (cursor), or re-derived (revision) or both.
      if (typeof res.cursor === "number" || derived) page.session?.setRevision(res.revision, res.cursor ?? null);
    });
    if (ok && page.project) page.project = { ...page.project, params: { ...page.project.params, ...body } };
    if (!ok) return false;
    if (derived) {
      // Derived from the cache: shown now. A job that came with it refines the ticks the cache could
      // only estimate, in the background (docs/API.md "Parameters").
      await page.loader.reload();
      this.updateInfo();
      if (job) await page.jobs.follow(job);
      return true;
    }
    if (job) await page.jobs.follow(job);
    this.updateInfo();
    return true;
  }

  async regenerate() {
    const page = this.page;
    const cfg = page.config;
    const p = (page.project && page.project.params) || {};
    let styles = [];
    try {
      styles = await page.api.listStyles();
    } catch (err) {
      toast(`Could not load the styles: ${errorText(err)}`, "error");
    }
    const params = await regenerateDialog({
      styles,
      style: p.style || null,
      presets: cfg.presets || ["balanced"],
      modes: cfg.modes || ["audio"],
      preset: p.preset || cfg.default_preset || "balanced",
      mode: p.mode || (cfg.modes && cfg.modes[0]) || "audio",
      thresholds: { ...this.thresholds },
    });
    if (!params) return;
    let res;
    try {
      res = await page.api.generate(page.projectId, params);
    } catch (err) {
      toast(`Could not start the generation: ${errorText(err)}`, "error");
      return;
    }
    await page.jobs.follow(res.job);
  }

  /**
   * Undo or redo stepped over a parameter change: its parameters are in force again (and a job
   * re-analyses the film when they need it).
   * @param {import("../../data/api.js").Params} params @param {import("../../data/api.js").Job|null} job
   */
  restored(params, job) {
    const page = this.page;
    if (page.project) page.project = { ...page.project, params };
    this.thresholds = { ...(params.thresholds || {}) };
    this.overrides = { ...(params.overrides || {}) };
    this.showThresholds();
    this.updateInfo();
    if (job) page.jobs.follow(job);
  }

  /** The preset and mode the timeline was made with, and its style in the header. */
  updateInfo() {
    const p = this.page.project && this.page.project.params;
    if (!p) return;
    this.info.textContent = `Preset ${p.preset} · mode ${p.mode}`;
    this.page.header.showStyle(p.style || null);
  }
}
