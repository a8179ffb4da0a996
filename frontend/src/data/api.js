/**
 * The HTTP client for docs/API.md. Every method maps to one route; errors become ApiError with the
 * server's one-sentence `detail` (./http.js); job progress and the chair's status come as
 * Server-Sent Events (./streams.js).
 */

import { postMultipart, reach } from "./http.js";
import { watchChair, watchJob } from "./streams.js";

/**
 * @typedef {{id: string, project_id: string, status: "queued"|"running"|"done"|"failed"|"cancelled",
 *   progress: number, stage?: string|null, error?: string|null}} Job
 * @typedef {{preset?: string, mode?: string, thresholds?: Record<string, number>,
 *   overrides?: Record<string, any>, style?: any}} Params
 * @typedef {{id: string, name: string, created_at?: string, updated_at?: string,
 *   status: "new"|"running"|"ready"|"failed"|"cancelled", duration_s?: number|null, n_ticks?: number|null,
 *   source?: any, job?: Job|null, params?: Params, revision?: number, cursor?: number, has_timeline?: boolean,
 *   media_type?: string, view?: Record<string, any>|null}} Project
 * @typedef {{id: string, t_s: number, label: string}} Marker
 * @typedef {{revision: number, cursor: number, ops: Array<Record<string, any>>, markers: Marker[]}} EditList
 * @typedef {{revision: number, cursor: number, markers: Marker[], params?: Params|null, job?: Job|null}} HistoryAnswer
 * @typedef {{points: number, duration_s: number, has_audio?: boolean, min: number[], max: number[]}} Waveform
 * @typedef {{device: string, description: string, kind: "usb"|"serial"|"virtual", likely_chair: boolean}} ChairPort
 * @typedef {{latency_ms: number, comfort: {scale: number, mute: Record<string, boolean>}}} ChairSettings
 * @typedef {{project_id: string, start_s: number, end_s: number, state: "running"|"done"|"cancelled"|"failed",
 *   progress: number, error: string|null}} ChairPush
 * @typedef {{connected: boolean, state: "idle"|"connected"|"reconnecting"|"disconnected"|"closed",
 *   port: string|null, capabilities: Record<string, any>|null, frames_sent: number, frames_dropped: number,
 *   last_tick: number|null, reconnects: number, diagnostics: Record<string, any>|null, error: string|null,
 *   playing: boolean, position_s: number,
 *   playback: {state: string, project_id: string|null, revision: number|null, ticks_skipped: number,
 *     drift_s: number|null, drift_seeks: number},
 *   push: ChairPush|null, settings: ChairSettings}} ChairStatus
 * @typedef {{project_id: string, state: "play"|"pause"|"seek", position_s: number, heartbeat?: boolean, initial?: boolean}} ChairReport
 * @typedef {{project_id: string, name: string, plain: Record<string, number|null>, styled: Record<string, number|null>,
 *   explained: number|null}} StyleFilm
 * @typedef {{id: string|null, name: string, created_at: string|null, films: Array<{project_id: string, name: string}>,
 *   report: StyleFilm[]}} StyleInfo
 */

export class Api {
  /** @param {string} [base] origin prefix, "" for the page's own origin */
  constructor(base = "") {
    this.base = base;
  }

  /**
   * @param {string} method
   * @param {string} path
   * @param {any} [body] JSON body
   * @returns {Promise<any>}
   */
  async request(method, path, body) {
    /** @type {RequestInit} */
    const init = { method, headers: { Accept: "application/json" } };
    if (body !== undefined) {
      init.body = JSON.stringify(body);
      init.headers = { ...init.headers, "Content-Type": "application/json" };
    }
    return this.readJson(fetch(this.base + path, init), `${method} ${path}`);
  }

  /**
   * Read a JSON response (a request made here, or one index.html started early).
   * @param {Promise<Response>} pending
   * @param {string} what "METHOD path", for messages
   * @returns {Promise<any>}
   */
  async readJson(pending, what) {
    const res = await reach(pending, what);
    if (res.status === 204) return null;
    const type = res.headers.get("Content-Type") || "";
    return type.includes("json") ? res.json() : res.text();
  }

  /**
   * Read a binary response.
   * @param {Promise<Response>} pending
   * @param {string} what
   * @returns {Promise<ArrayBuffer>}
   */
  async readBuffer(pending, what) {
    return (await reach(pending, what)).arrayBuffer();
  }

  /** @returns {Promise<Record<string, any>>} */
  config() {
    return this.request("GET", "/api/config");
  }

  /** @returns {Promise<Project[]>} */
  listProjects() {
    return this.request("GET", "/api/projects");
  }

  /** @param {string} id @returns {Promise<Project>} */
  project(id) {
    return this.request("GET", `/api/projects/${enc(id)}`);
  }

  /** @param {string} id @param {{name?: string, view?: Record<string, any>}} patch @returns {Promise<Project>} */
  patchProject(id, patch) {
    return this.request("PATCH", `/api/projects/${enc(id)}`, patch);
  }

  /** @param {string} id */
  deleteProject(id) {
    return this.request("DELETE", `/api/projects/${enc(id)}`);
  }

  /** @param {string} id @returns {Promise<Project>} */
  duplicateProject(id) {
    return this.request("POST", `/api/projects/${enc(id)}/duplicate`);
  }

  /** @param {string} id */
  mediaUrl(id) {
    return `${this.base}/api/projects/${enc(id)}/media`;
  }

  /** @param {string} id @param {number} points @returns {Promise<Waveform>} */
  waveform(id, points) {
    return this.request("GET", `/api/projects/${enc(id)}/waveform?points=${Math.round(points)}`);
  }

  /** @param {string} id @param {Params} params @returns {Promise<{job: Job}>} */
  generate(id, params) {
    return this.request("POST", `/api/projects/${enc(id)}/generate`, params);
  }

  /** @param {string} jobId @returns {Promise<Job>} */
  job(jobId) {
    return this.request("GET", `/api/jobs/${enc(jobId)}`);
  }

  /** @param {string} jobId */
  cancelJob(jobId) {
    return this.request("POST", `/api/jobs/${enc(jobId)}/cancel`);
  }

  /**
   * @param {string} id
   * @param {Params} params
   * @returns {Promise<{revision?: number, derived?: boolean, seconds?: number, job?: Job, cursor?: number|null}>}
   */
  putParams(id, params) {
    return this.request("PUT", `/api/projects/${enc(id)}/params`, params);
  }

  /** The composed timeline as native JSON (heavy for long films; used for markers and checks). */
  timeline(/** @type {string} */ id) {
    return this.request("GET", `/api/projects/${enc(id)}/timeline`);
  }

  /**
   * The binary timeline (docs/API.md "Binary timeline"); the browser asks for it gzipped and
   * revalidates a cached copy by its ETag.
   * @param {string} id
   * @param {"composed"|"generated"} [layer]
   * @param {string|null} [blocks] comma-separated block names (null: every block)
   * @param {number|null} [since] a revision held: its unchanged blocks are left out (named in the header)
   * @returns {Promise<ArrayBuffer>}
   */
  timelineBin(id, layer = "composed", blocks = null, since = null) {
    const path = this.timelineBinPath(id, layer, blocks, since);
    return this.readBuffer(fetch(this.base + path), `GET ${path}`);
  }

  /**
   * @param {string} id @param {"composed"|"generated"} [layer] @param {string|null} [blocks]
   * @param {number|null} [since]
   */
  timelineBinPath(id, layer = "composed", blocks = null, since = null) {
    return `/api/projects/${enc(id)}/timeline.bin?layer=${layer}${blocks ? `&blocks=${blocks}` : ""}` +
      `${since === null ? "" : `&since=${since}`}`;
  }

  /**
   * The composed temperature as the chair plays it (clamped, slew-limited) with the device's limits.
   * @param {string} id
   * @returns {Promise<{revision: number, tick_s: number, min_c: number, max_c: number, neutral_c: number,
   *   rate_c_per_s: number, values: number[]}>}
   */
  chairTemperature(id) {
    return this.request("GET", `/api/projects/${enc(id)}/timeline/chair-temperature`);
  }

  /**
   * Composed values of lanes over [t0, t1) at full precision, in the shape the `paste` op takes.
   * @param {string} id @param {string[]} lanes @param {number} t0 @param {number} t1
   * @returns {Promise<{revision: number, t0: number, t1: number, values: Record<string, any[]>}>}
   */
  laneValues(id, lanes, t0, t1) {
    const q = new URLSearchParams({ lanes: lanes.join(","), t0: String(t0), t1: String(t1) });
    return this.request("GET", `/api/projects/${enc(id)}/timeline/values?${q}`);
  }

  /** The shot list at the current revision (docs/API.md "Shots"). @param {string} id */
  shots(id) {
    return this.request("GET", `/api/projects/${enc(id)}/shots`);
  }

  /**
   * Every other shot by ascending distance (0..1) to one shot.
   * @param {string} id @param {number} shotId
   * @returns {Promise<{revision: number, shot: number, similar: Array<{id: number, distance: number}>}>}
   */
  similarShots(id, shotId) {
    return this.request("GET", `/api/projects/${enc(id)}/shots/${shotId}/similar`);
  }

  /** @param {string} id @returns {Promise<{frame_w: number, frame_h: number, per_tile: number, steps: number[]}>} */
  filmstrip(id) {
    return this.request("GET", `/api/projects/${enc(id)}/filmstrip`);
  }

  /** @param {string} id @param {number} step @param {number} tile */
  filmstripTileUrl(id, step, tile) {
    return `${this.base}/api/projects/${enc(id)}/filmstrip/${step}/${tile}.jpg`;
  }

  /** @param {string} id @returns {Promise<EditList>} */
  edits(id) {
    return this.request("GET", `/api/projects/${enc(id)}/edits`);
  }

  /**
   * @param {string} id
   * @param {number} baseRevision
   * @param {Record<string, any>} op
   * @returns {Promise<HistoryAnswer & {op: Record<string, any>}>}
   */
  postEdit(id, baseRevision, op) {
    return this.request("POST", `/api/projects/${enc(id)}/edits`, { base_revision: baseRevision, op });
  }

  /** @param {string} id @param {number} baseRevision @returns {Promise<HistoryAnswer>} */
  undo(id, baseRevision) {
    return this.request("POST", `/api/projects/${enc(id)}/undo`, { base_revision: baseRevision });
  }

  /** @param {string} id @param {number} baseRevision @returns {Promise<HistoryAnswer>} */
  redo(id, baseRevision) {
    return this.request("POST", `/api/projects/${enc(id)}/redo`, { base_revision: baseRevision });
  }

  /** @param {string} id @param {string} format */
  exportUrl(id, format) {
    return `${this.base}/api/projects/${enc(id)}/export?format=${encodeURIComponent(format)}`;
  }

  // ------------------------------------------------------------------ chair
  /** @returns {Promise<ChairPort[]>} */
  chairPorts() {
    return this.request("GET", "/api/chair/ports");
  }

  /** @param {string} port @returns {Promise<ChairStatus>} */
  chairConnect(port) {
    return this.request("POST", "/api/chair/connect", { port });
  }

  /** @returns {Promise<ChairStatus>} */
  chairDisconnect() {
    return this.request("POST", "/api/chair/disconnect");
  }

  /** @returns {Promise<ChairStatus>} */
  chairStatus() {
    return this.request("GET", "/api/chair/status");
  }

  /** What the player does (play / pause / seek at a position); the chair follows it. @param {ChairReport} report @returns {Promise<ChairStatus>} */
  chairPlayback(report) {
    return this.request("POST", "/api/chair/playback", report);
  }

  /**
   * STOP: every output of the chair off now. Sent with keepalive so it still goes out while the
   * page unloads.
   * @returns {Promise<ChairStatus>}
   */
  chairStop() {
    const path = "/api/chair/stop";
    return this.readJson(fetch(this.base + path, { method: "POST", keepalive: true, headers: { Accept: "application/json" } }), `POST ${path}`);
  }

  /**
   * @param {{latency_ms?: number, comfort?: {scale?: number, mute?: Record<string, boolean>}}} settings
   * @returns {Promise<ChairSettings>}
   */
  putChairSettings(settings) {
    return this.request("PUT", "/api/chair/settings", settings);
  }

  /** @param {string} id @param {number} startS @param {number} endS @returns {Promise<ChairStatus>} */
  chairPush(id, startS, endS) {
    return this.request("POST", "/api/chair/push", { project_id: id, start_s: startS, end_s: endS });
  }

  /**
   * Follow the chair's status (Server-Sent Events `status`; EventSource reconnects by itself).
   * @param {(status: ChairStatus) => void} onStatus
   * @param {(connected: boolean) => void} [onStream] the stream opened (true) or dropped (false)
   * @returns {() => void} closes the stream
   */
  watchChair(onStatus, onStream = () => {}) {
    return watchChair(`${this.base}/api/chair/events`, onStatus, onStream);
  }

  /**
   * Upload a media file (multipart field `file`) with upload progress.
   * @param {File} file
   * @param {Record<string, string>} fields extra form fields (name, preset, mode, generate)
   * @param {(fraction: number, loaded: number, total: number) => void} onProgress
   * @returns {{promise: Promise<Project>, abort: () => void}}
   */
  upload(file, fields, onProgress) {
    return this._multipart("/api/projects", file, fields, onProgress);
  }

  /**
   * Import our JSON or CSV as an undoable `import` op, refused (409) unless the project is still
   * at `baseRevision`.
   * @param {string} id
   * @param {File} file
   * @param {number} baseRevision
   * @returns {{promise: Promise<HistoryAnswer & {op: Record<string, any>}>, abort: () => void}}
   */
  importFile(id, file, baseRevision) {
    return this._multipart(`/api/projects/${enc(id)}/import`, file, { base_revision: String(baseRevision) }, () => {});
  }

  /**
   * @param {string} path
   * @param {File} file
   * @param {Record<string, string>} fields
   * @param {(fraction: number, loaded: number, total: number) => void} onProgress
   */
  _multipart(path, file, fields, onProgress) {
    return postMultipart(this.base + path, path, file, fields, onProgress);
  }

  /** @returns {Promise<StyleInfo[]>} the stored styles, newest first */
  listStyles() {
    return this.request("GET", "/api/styles");
  }

  /**
   * Learn a style from projects' edits; `dryRun`: the report only, nothing stored.
   * @param {string} name @param {string[]} projectIds @param {boolean} dryRun
   * @returns {Promise<StyleInfo & {document: Record<string, any>}>}
   */
  learnStyle(name, projectIds, dryRun) {
    return this.request("POST", "/api/styles", { name, project_ids: projectIds, dry_run: dryRun });
  }

  /** @param {string} id */
  deleteStyle(id) {
    return this.request("DELETE", `/api/styles/${enc(id)}`);
  }

  /** @param {string} id the style file's download URL */
  styleDownloadUrl(id) {
    return `${this.base}/api/styles/${enc(id)}/download`;
  }

  /** @param {File} file a style file @returns {{promise: Promise<StyleInfo>, abort: () => void}} */
  importStyle(file) {
    return this._multipart("/api/styles/import", file, {}, () => {});
  }

  /**
   * Follow a job's Server-Sent Events until it ends.
   * @param {string} jobId
   * @param {(progress: number, stage: string) => void} onProgress
   * @returns {{promise: Promise<Job>, close: () => void}} resolves with the final job (done, failed or cancelled)
   */
  watchJob(jobId, onProgress) {
    return watchJob(`${this.base}/api/jobs/${enc(jobId)}/events`, jobId, () => this.job(jobId), onProgress);
  }
}

/** @param {string} s */
function enc(s) {
  return encodeURIComponent(s);
}
