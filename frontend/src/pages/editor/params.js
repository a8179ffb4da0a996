/**
 * The generation parameters in the editor: the thresholds (sliders and the lines on the feature
 * lanes, live while dragged, committed on release), the preset and mode line, and Regenerate.
 */

import { h } from "../../core/dom.js";
import { errorText } from "../../data/http.js";
import { regenerateDialog } from "../../panels/regenerate.js";
import { ThresholdsPanel } from "../../panels/thresholds.js";
import { toast } from "../../panels/widgets.js";

export class ParamsControl {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {Record<string, number>} */
    this.thresholds = { ...(page.config.default_thresholds || {}) };
    /** @type {ThresholdsPanel|null} */
    this.panel = null;
    this.info = h("p", { class: "params-info", "data-testid": "params-info" });
  }

  /** The thresholds panel. @param {string[]} features */
  build(features) {
    this.panel = new ThresholdsPanel(features, {
      onInput: (name, v) => this.input(name, v),
      onCommit: (name, v) => this.commit(name, v),
    });
    this.showThresholds();
    return this.panel.el;
  }

  /** Take the project's thresholds (when it has its own). @param {import("../../data/api.js").Project} project */
  takeThresholds(project) {
    if (project.params && project.params.thresholds) this.thresholds = { ...project.params.thresholds };
  }

  showThresholds() {
    for (const [n, v] of Object.entries(this.thresholds)) this.panel.set(n, v);
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
    const thresholds = { ...this.thresholds };
    /** @type {import("../../data/api.js").Job|null} */
    let job = null;
    let derived = false;
    const ok = await page.session.run(async () => {
      const res = await page.api.putParams(page.projectId, { thresholds });
      if (res.job) job = res.job;
      if (res.derived && typeof res.revision === "number") {
        derived = true;
        page.session?.setRevision(res.revision);
      }
    });
    if (!ok) {
      this.thresholds = { ...this.thresholds, [name]: before };
      this.panel.set(name, before);
      page.timeline.invalidate();
      return;
    }
    if (derived) {
      // Derived from the cache: shown now. A job that came with it refines the ticks the cache could
      // only estimate, in the background (docs/API.md "Parameters").
      await page.loader.reload();
      this.updateInfo();
      if (job) await page.jobs.follow(job);
      return;
    }
    if (job) await page.jobs.follow(job);
    this.updateInfo();
  }

  async regenerate() {
    const page = this.page;
    const cfg = page.config;
    const p = (page.project && page.project.params) || {};
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
      res = await page.api.generate(page.projectId, params);
    } catch (err) {
      toast(`Could not start the generation: ${errorText(err)}`, "error");
      return;
    }
    await page.jobs.follow(res.job);
  }

  /** The preset and mode the timeline was made with. */
  updateInfo() {
    const p = this.page.project && this.page.project.params;
    if (!p) return;
    this.info.textContent = `Preset ${p.preset} · mode ${p.mode}`;
  }
}
