/**
 * Generation jobs seen from the editor: the progress bar while one runs (Regenerate, a threshold
 * that needs a fresh analysis, or a job already running when the editor opened), and afterwards
 * the project, its parameters and its timeline read again.
 */

import { h } from "../../core/dom.js";
import { errorText } from "../../data/http.js";
import { JobProgress } from "../../panels/job-progress.js";
import { toast } from "../../panels/widgets.js";

/** How long the finished progress bar stays. */
const DONE_SHOWN_MS = 2500;

export class JobFollower {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** Jobs being followed (progress shown); a threshold re-derive may bring a background one. */
    this.followed = 0;
    /** @type {JobProgress|null} */
    this.progress = null;
  }

  /** The slot the progress bar shows in. */
  build() {
    this.slot = h("div", { class: "job-slot", hidden: true, "data-testid": "job-slot" });
    return this.slot;
  }

  /** @param {import("../../data/api.js").Job} job */
  async follow(job) {
    this.followed += 1;
    try {
      await this._follow(job);
    } finally {
      this.followed -= 1;
    }
  }

  /** @param {import("../../data/api.js").Job} job */
  async _follow(job) {
    const page = this.page;
    const { regenBtn } = page.header;
    const params = page.params;
    if (this.progress) this.progress.close();
    const progress = new JobProgress(page.api);
    this.progress = progress;
    this.slot.replaceChildren(progress.el);
    this.slot.hidden = false;
    regenBtn.disabled = true;
    params.panel.setDisabled(true);
    let final;
    try {
      final = await progress.follow(job);
    } catch (err) {
      regenBtn.disabled = false;
      return;
    }
    if (page.disposed) return;
    regenBtn.disabled = false;
    try {
      page.project = await page.api.project(page.projectId);
    } catch (err) {
      toast(`Could not reload the project: ${errorText(err)}`, "error");
      return;
    }
    params.takeThresholds(page.project);
    params.showThresholds();
    params.updateInfo();
    if (final.status === "done") {
      page.hideNotice();
      params.panel.setDisabled(false);
      if (page.session) await page.session.reload();
      else await page.loader.reload();
      setTimeout(() => {
        if (this.progress === progress) this.slot.hidden = true;
      }, DONE_SHOWN_MS);
    } else {
      // The project is back to the timeline on show (its parameters, read above); the bar says how
      // the attempt ended, then goes.
      params.panel.setDisabled(!page.project.has_timeline);
      if (final.status === "failed") toast(`Generation failed: ${final.error || "unknown error"}`, "error", 10000);
      setTimeout(() => {
        if (this.progress === progress) this.slot.hidden = true;
      }, DONE_SHOWN_MS);
    }
  }

  close() {
    if (this.progress) this.progress.close();
  }
}
