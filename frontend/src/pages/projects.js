/**
 * The projects screen: upload (drag-and-drop or file picker) with an upload progress bar, then the
 * generation progress with Cancel, in a learned style when one is chosen; the list of projects
 * with open, rename, duplicate, delete and Learn style; the learned styles.
 */

import { isTerminal } from "../data/streams.js";
import { h } from "../core/dom.js";
import { confirmDialog, progressBar, promptDialog, toast } from "../panels/widgets.js";
import { formatBytes, formatDate, formatTime } from "../data/format.js";
import { errorText } from "../data/http.js";
import { JobProgress } from "../panels/job-progress.js";
import { learnStyleDialog } from "../panels/learn-style.js";
import { StylesPanel } from "../panels/styles-panel.js";

const STATUS_TEXT = /** @type {Record<string, string>} */ ({
  new: "no timeline",
  running: "generating",
  ready: "ready",
  failed: "failed",
  cancelled: "cancelled",
});

export class ProjectsPage {
  /**
   * @param {HTMLElement} host
   * @param {{config: Record<string, any>, api: import("../data/api.js").Api}} ctx
   */
  constructor(host, ctx) {
    this.host = host;
    this.api = ctx.api;
    this.config = ctx.config;
    /** @type {Map<string, {close: () => void}>} job watchers of the list rows */
    this.watchers = new Map();
    /** @type {Map<string, {el: HTMLElement, set: (fraction: number, note?: string) => void}>} the rows' job bars */
    this.rowBars = new Map();
    /** @type {Map<string, number>} how many projects bear each name */
    this.names = new Map();
    /** @type {JobProgress|null} */
    this.uploadJob = null;
    /** @type {{abort: () => void}|null} */
    this.uploading = null;
    this.disposed = false;
  }

  async open() {
    document.title = "Projects · autohaptics";
    this._build();
    await this.refresh();
  }

  _build() {
    const accept = "video/*,audio/*,.mkv,.webm,.mp4,.mov,.avi,.m4v";
    this.fileInput = h("input", { type: "file", accept, class: "visually-hidden", "data-testid": "file-input", "aria-label": "Choose a video file" });
    this.fileInput.addEventListener("change", () => {
      const f = this.fileInput.files && this.fileInput.files[0];
      if (f) this.upload(f);
      this.fileInput.value = "";
    });
    const pick = h("button", { class: "btn btn-primary", type: "button", "data-testid": "choose-file", onclick: () => this.fileInput.click() }, "Choose a video…");
    this.presetSel = h("select", { class: "input", "data-testid": "upload-preset", "aria-label": "Quality preset" });
    for (const p of this.config.presets || ["balanced"]) this.presetSel.add(new Option(p, p, false, p === (this.config.default_preset || "balanced")));
    this.generateCb = h("input", { type: "checkbox", checked: true, "data-testid": "upload-generate" });
    this.styleSel = h("select", { class: "input", "data-testid": "upload-style", "aria-label": "Style" });
    this.styleSel.add(new Option("None", ""));
    const limit = Number(this.config.upload_limit_bytes);
    this.drop = h(
      "div",
      { class: "dropzone", "data-testid": "dropzone", tabindex: "0", role: "button", "aria-label": "Drop a video here or press Enter to choose one" },
      h("p", { class: "dropzone-title" }, "Drop a video here"),
      h("p", { class: "dropzone-hint" }, `or `, pick, Number.isFinite(limit) ? ` · up to ${formatBytes(limit)}` : ""),
      h("div", { class: "upload-options" },
        h("label", { class: "field-inline" }, "Preset ", this.presetSel),
        h("label", { class: "field-inline" }, "Style ", this.styleSel),
        h("label", { class: "field-inline" }, this.generateCb, " Generate after upload")),
      this.fileInput,
    );
    this.drop.addEventListener("keydown", (e) => {
      if ((e.key === "Enter" || e.key === " ") && e.target === this.drop) {
        e.preventDefault();
        this.fileInput.click();
      }
    });
    for (const type of ["dragenter", "dragover"]) {
      this.drop.addEventListener(type, (e) => {
        e.preventDefault();
        this.drop.classList.add("dragging");
      });
    }
    for (const type of ["dragleave", "drop"]) this.drop.addEventListener(type, () => this.drop.classList.remove("dragging"));
    this.drop.addEventListener("drop", (e) => {
      e.preventDefault();
      const f = e.dataTransfer && e.dataTransfer.files[0];
      if (f) this.upload(f);
    });

    this.uploadBar = progressBar("Upload progress", "upload-progress");
    this.uploadName = h("span", { class: "upload-name", "data-testid": "upload-name" });
    this.uploadCancel = h("button", { class: "btn btn-small", type: "button", "data-testid": "upload-cancel", onclick: () => this.uploading && this.uploading.abort() }, "Cancel");
    this.uploadStatus = h("div", { class: "upload-status", role: "status", "aria-live": "polite", "data-testid": "upload-status" });
    this.uploadJobSlot = h("div", { class: "upload-job" });
    this.uploadOpen = h("a", { class: "btn btn-primary", hidden: true, "data-testid": "open-uploaded" }, "Open in the editor");
    this.uploadBox = h(
      "div",
      { class: "upload-box", hidden: true, "data-testid": "upload-box" },
      h("div", { class: "upload-row" }, h("span", { class: "upload-label" }, "Upload"), this.uploadName),
      h("div", { class: "upload-row" }, this.uploadBar.el, this.uploadCancel),
      this.uploadJobSlot,
      this.uploadStatus,
      this.uploadOpen,
    );

    this.listEl = h("ul", { class: "project-list", "data-testid": "project-list", "aria-label": "Projects" });
    this.stylesPanel = new StylesPanel(this.api, () => this.refreshStyles());
    this.emptyEl = h("p", { class: "empty", hidden: true, "data-testid": "no-projects" }, "No projects yet: drop a video above to start.");
    this.host.replaceChildren(
      h("header", { class: "topbar" }, h("span", { class: "brand" }, "autohaptics"), h("h1", { class: "page-title" }, "Projects")),
      h("main", { class: "projects", "data-testid": "projects-page" },
        h("section", { class: "panel upload-panel", "aria-label": "Upload" }, this.drop, this.uploadBox),
        h("section", { class: "panel" }, h("h2", { class: "panel-title" }, "Your projects"), this.listEl, this.emptyEl),
        this.stylesPanel.el),
    );
  }

  /** Reload the project list. */
  async refresh() {
    let projects;
    try {
      projects = await this.api.listProjects();
    } catch (err) {
      toast(`Could not load the projects: ${errorText(err)}`, "error");
      return;
    }
    if (this.disposed) return;
    for (const w of this.watchers.values()) w.close();
    this.watchers.clear();
    this.rowBars.clear();
    this.names = new Map();
    for (const p of projects) this.names.set(p.name, (this.names.get(p.name) || 0) + 1);
    this.listEl.replaceChildren(...projects.map((p) => this._row(p)));
    this.emptyEl.hidden = projects.length > 0;
    await this.refreshStyles();
  }

  /** Reload the Style select's options (the learned styles), keeping the choice while it exists. */
  async refreshStyles() {
    let styles;
    try {
      styles = await this.api.listStyles();
    } catch (err) {
      toast(`Could not load the styles: ${errorText(err)}`, "error");
      return;
    }
    if (this.disposed) return;
    this.stylesPanel.show(styles);
    const chosen = this.styleSel.value;
    this.styleSel.replaceChildren(new Option("None", ""), ...styles.map((st) => new Option(st.name, st.id || "", false, st.id === chosen)));
  }

  /** Learn a style from a project's edits (the dialog shows the report before saving). @param {import("../data/api.js").Project} p */
  async learnStyle(p) {
    const style = await learnStyleDialog(this.api, p);
    if (!style) return;
    toast(`Saved the style “${style.name}”.`);
    await this.refreshStyles();
  }

  /** @param {import("../data/api.js").Project} p */
  _row(p) {
    const open = h("a", { class: "project-name-link", href: `#/project/${encodeURIComponent(p.id)}`, "data-testid": "project-open" }, p.name);
    const status = h("span", { class: `badge badge-${p.status}`, "data-testid": "project-status" }, STATUS_TEXT[p.status] || p.status);
    const meta = h("span", { class: "project-meta", "data-testid": "project-meta" }, this._meta(p));
    const btn = (/** @type {string} */ text, /** @type {string} */ testid, /** @type {() => void} */ fn) =>
      h("button", { class: "btn btn-small", type: "button", "data-testid": testid, "aria-label": `${text} ${p.name}`, onclick: fn }, text);
    const row = h(
      "li",
      { class: "project-row", "data-testid": "project-row", "data-id": p.id, "data-status": p.status },
      h("div", { class: "project-main" }, open, status, meta),
      h("div", { class: "project-actions" },
        btn("Open", "project-open-btn", () => { location.hash = `#/project/${encodeURIComponent(p.id)}`; }),
        btn("Rename", "project-rename", () => this.rename(p)),
        btn("Duplicate", "project-duplicate", () => this.duplicate(p)),
        p.has_timeline ? btn("Learn style…", "project-learn-style", () => this.learnStyle(p)) : null,
        btn("Delete", "project-delete", () => this.remove(p))),
    );
    const job = p.job;
    if (p.has_timeline && job && (job.status === "cancelled" || job.status === "failed")) {
      row.append(h("p", { class: "project-note", "data-testid": "project-note" },
        `Last regeneration ${job.status}${job.error ? ` (${job.error})` : ""}; the previous timeline is kept.`));
    }
    if (job && !isTerminal(job.status)) {
      const bar = progressBar(`Generation of ${p.name}`, "row-progress");
      bar.set(job.progress || 0);
      this.rowBars.set(p.id, bar);
      row.append(bar.el);
      const w = this.api.watchJob(job.id, (f) => bar.set(f));
      this.watchers.set(p.id, w);
      w.promise.then(() => this.refresh(), () => this.refresh());
    }
    return row;
  }

  /**
   * Duration, the picture's size, when it was made and changed; projects of the same name also
   * show their file and id, so two of them are told apart.
   * @param {import("../data/api.js").Project} p
   */
  _meta(p) {
    const video = p.source && p.source.video;
    const twins = this.names.get(p.name) > 1;
    return [
      p.duration_s ? formatTime(p.duration_s) : "",
      video ? `${video.width}x${video.height}` : "",
      twins && p.source && p.source.size_bytes ? formatBytes(p.source.size_bytes) : "",
      twins && p.created_at ? `created ${formatDate(p.created_at)}` : "",
      `changed ${formatDate(p.updated_at)}`,
      twins ? `id ${p.id.slice(0, 6)}` : "",
    ].filter(Boolean).join(" · ");
  }

  /** @param {import("../data/api.js").Project} p */
  async rename(p) {
    const name = await promptDialog({ title: "Rename the project", label: "Name", value: p.name, ok: "Rename" });
    if (name === null || name === p.name || !name) return;
    try {
      await this.api.patchProject(p.id, { name });
    } catch (err) {
      toast(`Could not rename: ${errorText(err)}`, "error");
    }
    await this.refresh();
  }

  /** @param {import("../data/api.js").Project} p */
  async duplicate(p) {
    try {
      const copy = await this.api.duplicateProject(p.id);
      toast(`Duplicated as “${copy.name}”.`);
    } catch (err) {
      toast(`Could not duplicate: ${errorText(err)}`, "error");
    }
    await this.refresh();
  }

  /** @param {import("../data/api.js").Project} p */
  async remove(p) {
    const ok = await confirmDialog({
      title: "Delete the project?",
      message: `“${p.name}”, its media, its timeline and its edits will be deleted. This cannot be undone.`,
      ok: "Delete",
      danger: true,
    });
    if (!ok) return;
    try {
      await this.api.deleteProject(p.id);
      toast(`Deleted “${p.name}”.`);
    } catch (err) {
      toast(`Could not delete: ${errorText(err)}`, "error");
    }
    await this.refresh();
  }

  /**
   * Upload a file, then follow its generation job.
   * @param {File} file
   */
  async upload(file) {
    if (this.uploading) {
      toast("An upload is already running.", "warn");
      return;
    }
    const limit = Number(this.config.upload_limit_bytes);
    if (Number.isFinite(limit) && file.size > limit) {
      toast(`${file.name} is ${formatBytes(file.size)}; the limit is ${formatBytes(limit)}.`, "error");
      return;
    }
    this.uploadBox.hidden = false;
    this.uploadOpen.hidden = true;
    this.uploadName.textContent = `${file.name} (${formatBytes(file.size)})`;
    this.uploadStatus.textContent = "Uploading…";
    this.uploadStatus.classList.remove("error");
    this.uploadCancel.hidden = false;
    this.uploadBar.set(0);
    this.uploadJobSlot.replaceChildren();
    const generate = this.generateCb.checked;
    const task = this.api.upload(
      file,
      { name: file.name.replace(/\.[^.]+$/, ""), preset: this.presetSel.value, generate: String(generate), ...(this.styleSel.value ? { style: this.styleSel.value } : {}) },
      (f) => this.uploadBar.set(f),
    );
    this.uploading = task;
    let project;
    try {
      project = await task.promise;
    } catch (err) {
      this.uploadStatus.textContent = errorText(err);
      this.uploadStatus.classList.add("error");
      return;
    } finally {
      this.uploading = null;
      this.uploadCancel.hidden = true;
    }
    this.uploadBar.set(1);
    this.uploadStatus.textContent = generate ? "Uploaded; generating the timeline…" : "Uploaded.";
    this.uploadOpen.setAttribute("href", `#/project/${encodeURIComponent(project.id)}`);
    this.uploadOpen.hidden = false;
    await this.refresh();
    if (project.job && !isTerminal(project.job.status)) {
      // The upload box follows this job; the list row needs no second watcher.
      const rowWatch = this.watchers.get(project.id);
      if (rowWatch) rowWatch.close();
      const jp = new JobProgress(this.api, { onProgress: (f) => this.rowBars.get(project.id)?.set(f) });
      this.uploadJob = jp;
      this.uploadJobSlot.replaceChildren(h("span", { class: "upload-label" }, "Generation"), jp.el);
      try {
        const final = await jp.follow(project.job);
        this.uploadStatus.textContent =
          final.status === "done" ? "Ready: open it in the editor." : final.status === "cancelled" ? "Generation cancelled." : `Generation failed: ${final.error || "unknown error"}`;
      } catch (err) {
        this.uploadStatus.textContent = errorText(err);
      }
      if (!this.disposed) await this.refresh();
    }
  }

  destroy() {
    this.disposed = true;
    for (const w of this.watchers.values()) w.close();
    if (this.uploadJob) this.uploadJob.close();
    if (this.uploading) this.uploading.abort();
  }
}
