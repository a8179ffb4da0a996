/**
 * A generation job's progress bar with a Cancel button, fed by the job's Server-Sent Events.
 */

import { errorText } from "../data/http.js";
import { h } from "../core/dom.js";
import { progressBar } from "./widgets.js";

const STAGES = /** @type {Record<string, string>} */ ({
  queued: "queued",
  hash: "reading",
  audio: "analysing sound",
  video: "analysing picture",
  derive: "building tracks",
  done: "done",
});

export class JobProgress {
  /**
   * @param {import("../data/api.js").Api} api
   * @param {{label?: string, testid?: string, onProgress?: (fraction: number) => void}} [opts]
   *   onProgress: every figure this bar shows, for another view of the same job (one figure everywhere)
   */
  constructor(api, opts = {}) {
    this.api = api;
    this.onProgress = opts.onProgress || (() => {});
    this.fraction = 0;
    this.bar = progressBar(opts.label || "Generation progress", opts.testid || "generation-progress");
    this.cancelBtn = h("button", { class: "btn btn-small", type: "button", "data-testid": "generation-cancel" }, "Cancel");
    this.status = h("span", { class: "job-status", "data-testid": "generation-status" });
    this.el = h("div", { class: "job-progress" }, this.bar.el, this.cancelBtn, this.status);
    /** @type {{promise: Promise<import("../data/api.js").Job>, close: () => void}|null} */
    this.watch = null;
    /** @type {string|null} */
    this.jobId = null;
    /** the job's end has been shown (a late answer to Cancel must not cover it) */
    this.ended = false;
    this.cancelBtn.addEventListener("click", () => this.cancel());
  }

  /**
   * Follow a job until it ends; resolves with the final job.
   * @param {import("../data/api.js").Job} job
   * @returns {Promise<import("../data/api.js").Job>}
   */
  async follow(job) {
    this.close();
    this.jobId = job.id;
    this.ended = false;
    this.cancelBtn.disabled = false;
    this._show(job.progress || 0, STAGES[job.stage || job.status] || job.stage || job.status);
    this.status.textContent = "";
    this.watch = this.api.watchJob(job.id, (p, stage) => this._show(p, STAGES[stage] || stage));
    let final;
    try {
      final = await this.watch.promise;
    } catch (err) {
      this.status.textContent = errorText(err);
      this.cancelBtn.disabled = true;
      throw err;
    }
    this.cancelBtn.disabled = true;
    this.ended = true;
    if (final.status === "done") {
      this._show(1, "done");
      this.status.textContent = "Generation finished.";
    } else if (final.status === "cancelled") {
      this.bar.set(this.fraction, "cancelled");
      this.status.textContent = "Generation cancelled; the previous timeline stays.";
    } else {
      this.bar.set(this.fraction, "failed");
      this.status.textContent = `Generation failed: ${final.error || "unknown error"}`;
    }
    return final;
  }

  /** @param {number} fraction 0..1 @param {string} note */
  _show(fraction, note) {
    this.fraction = fraction;
    this.bar.set(fraction, note);
    this.onProgress(fraction);
  }

  async cancel() {
    if (!this.jobId) return;
    this.cancelBtn.disabled = true;
    try {
      await this.api.cancelJob(this.jobId);
      if (!this.ended) this.status.textContent = "Cancelling…";
    } catch (err) {
      if (this.ended) return;
      this.status.textContent = `Could not cancel: ${errorText(err)}`;
      this.cancelBtn.disabled = false;
    }
  }

  close() {
    if (this.watch) this.watch.close();
    this.watch = null;
  }
}
