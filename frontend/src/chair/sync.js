/**
 * Keeps the chair in step with the player while a chair is connected (docs/API.md "Chair"): the
 * player's `sync` events go to POST /api/chair/playback as play / pause / seek reports, and while
 * the picture advances a heartbeat goes out every second. The server's own 10 Hz clock sends the
 * frames; the reports anchor it and correct its drift. A heartbeat never restarts a stopped chair,
 * so after STOP only the viewer's next play does.
 *
 * On connecting, the page tells the chair where its player is (an `initial` report: not a viewer's
 * action, so it leaves a push that is running alone).
 *
 * Reports go out one at a time, in order. A heartbeat is skipped while another report is pending,
 * and the position of a play report or heartbeat is read when it is sent, not when it was queued.
 * `halt()` drops whatever is still queued (used by STOP).
 */

import { ApiError } from "../data/http.js";

export const HEARTBEAT_MS = 1000;

export class ChairSync {
  /**
   * @param {import("../data/api.js").Api} api
   * @param {string} projectId
   * @param {import("../core/player.js").Player} player
   * @param {{onError?: (message: string) => void, heartbeatMs?: number}} [opts]
   */
  constructor(api, projectId, player, opts = {}) {
    this.api = api;
    this.projectId = projectId;
    this.player = player;
    this.onError = opts.onError || (() => {});
    this.heartbeatMs = opts.heartbeatMs || HEARTBEAT_MS;
    this.active = false;
    /** the picture advances (between a "play" and a "pause" sync event) */
    this.running = player.playing;
    this.pending = 0;
    /** @type {Promise<void>|null} the report being sent now */
    this.inflight = null;
    this.generation = 0;
    /** @type {Promise<any>} */
    this.chain = Promise.resolve();
    /** @type {ReturnType<typeof setInterval>|null} */
    this.timer = null;
    this.off = player.on("sync", ({ state, timeS }) => this._onSync(state, timeS));
  }

  /**
   * A chair is connected (or reconnecting) or not. On connecting, the chair learns where the
   * player is at once: it starts playing with it, or loads the timeline at the position.
   * @param {boolean} active
   */
  setActive(active) {
    if (active === this.active) return;
    this.active = active;
    if (active) {
      if (this.running) this._send("play", null, { initial: true });
      else this._send("seek", this.player.currentTime, { initial: true });
    }
    this._updateTimer();
  }

  /**
   * Drop the reports still queued (after STOP, nothing from before it may restart the chair).
   * Returns the report already on its way to the server, if any: it may arrive after the STOP
   * (requests travel on separate connections), so the caller stops again once it has landed.
   * @returns {Promise<void>|null}
   */
  halt() {
    this.generation++;
    return this.inflight;
  }

  /** @param {"play"|"pause"|"seek"} state @param {number} timeS */
  _onSync(state, timeS) {
    if (state === "play") this.running = true;
    else if (state === "pause") this.running = false;
    this._updateTimer();
    if (!this.active) return;
    if (state === "play") this._send("play");
    else this._send(state, timeS);
  }

  _updateTimer() {
    const want = this.active && this.running;
    if (want && !this.timer) {
      this.timer = setInterval(() => {
        if (this.pending === 0 && this.running && this.active) this._send("play", null, { heartbeat: true });
      }, this.heartbeatMs);
    } else if (!want && this.timer) {
      clearInterval(this.timer);
      this.timer = null;
    }
  }

  /**
   * Queue one report. `timeS` null: the player's position when the report is sent.
   * @param {"play"|"pause"|"seek"} state
   * @param {number|null} [timeS]
   * @param {{heartbeat?: boolean, initial?: boolean, last?: boolean}} [kind] a heartbeat; the page's
   *   report on connecting; the final report of this page (sent although it is no longer active)
   */
  _send(state, timeS = null, { heartbeat = false, initial = false, last = false } = {}) {
    const generation = this.generation;
    this.pending++;
    this.chain = this.chain.then(async () => {
      try {
        if (generation !== this.generation || !(this.active || last)) return;
        const position = Math.max(0, timeS === null ? this.player.currentTime : timeS);
        /** @type {import("../data/api.js").ChairReport} */
        const report = { project_id: this.projectId, state, position_s: Math.round(position * 1000) / 1000 };
        if (heartbeat) report.heartbeat = true;
        if (initial) report.initial = true;
        const sending = this.api.chairPlayback(report);
        this.inflight = sending.then(() => {}, () => {});
        await sending;
      } catch (err) {
        // 409: the chair went away meanwhile; the panel shows that from the status stream.
        if (!(err instanceof ApiError && err.status === 409) && !heartbeat) this.onError(err instanceof Error ? err.message : String(err));
      } finally {
        this.inflight = null;
        this.pending--;
      }
    });
  }

  destroy() {
    this.off();
    if (this.active && this.running) this._send("pause", this.player.currentTime, { last: true });
    this.active = false;
    this._updateTimer();
  }
}
