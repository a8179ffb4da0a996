/**
 * The picture and the playhead: the <video> with the fan-grid overlay, the player that clocks the
 * editor, the transport bar (play, time, zoom, follow, overlay, the lane and key menus), and what
 * is shown at the playhead (the time, the overlay; the chair diagram is ./chair.js's). The
 * playhead is kept per project in this browser (data/local-store.js), so a reload finds it again.
 */

import { h } from "../../core/dom.js";
import { Player } from "../../core/player.js";
import { FanOverlay } from "../../chair/fan-overlay.js";
import { formatTime } from "../../data/format.js";
import { errorText } from "../../data/http.js";
import { readLocal, writeLocal } from "../../data/local-store.js";
import { toast } from "../../panels/widgets.js";
import { ZOOM_STEP, keysMenu } from "./keys.js";

/** While playing, the kept playhead is written at most this often (ms). */
const KEEP_PLAYHEAD_MS = 1000;

export class EditorMedia {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {Player|null} */
    this.player = null;
    /** @type {FanOverlay|null} */
    this.fanOverlay = null;
    /** the tick whose values are shown (-1: show them again) */
    this.lastTick = -1;
    /** when the playhead was last kept (performance.now(), ms); null until the kept one is restored */
    this._keptAt = /** @type {number|null} */ (null);
  }

  /** The video with the fan overlay over it, and the player. @param {number} durationS */
  buildVideo(durationS) {
    // The media source is set once the timeline is drawn (attach), so the video's first range
    // requests do not compete with timeline.bin for the server.
    this.video = h("video", { class: "video", preload: "auto", playsinline: true, "data-testid": "video" });
    const overlay = h("canvas", { class: "fan-overlay", hidden: true, tabindex: "0", "data-testid": "fan-overlay",
      "aria-label": "Fan grid at the playhead: drag to pick a rectangle of fans for Set, Scale, Clear and the fades, Ctrl+drag to paint, Escape to clear" });
    const { fanRows, fanCols } = this.page.layout;
    this.fanOverlay = new FanOverlay(overlay, this.video, { rows: fanRows, cols: fanCols });
    this.fanOverlay.onRegion = (cells) => this.page.edits.takeRegion(cells);
    this.player = new Player(this.video, { durationS, frameLoop: this.page.loop });
    return h("div", { class: "video-wrap" }, this.video, overlay);
  }

  /** The transport bar: playback and view controls. @param {number} durationS */
  buildTransport(durationS) {
    const page = this.page;
    const zoom = (/** @type {number} */ f) => page.timeline.zoomBy(f);
    this.playBtn = h("button", { class: "btn btn-primary btn-play", type: "button", "data-testid": "play", "aria-label": "Play (Space)", onclick: () => this.togglePlay() }, "▶");
    this.timeEl = h("span", { class: "time", "data-testid": "time" }, `0:00.0 / ${formatTime(durationS)}`);
    this.overlayBtn = h("button", { class: "btn", type: "button", "aria-pressed": "false", "data-testid": "toggle-fan-overlay", onclick: () => this.setOverlay(!this.fanOverlay.visible) }, "Fan grid");
    this.followBtn = h("button", { class: "btn", type: "button", "aria-pressed": "true", "data-testid": "toggle-follow", title: "Keep the playhead in view while playing", onclick: () => this.setFollow(!page.timeline.follow) }, "Follow");
    const zoomOut = h("button", { class: "btn", type: "button", "aria-label": "Zoom out (-)", "data-testid": "zoom-out", onclick: () => zoom(1 / ZOOM_STEP) }, "−");
    const zoomFit = h("button", { class: "btn", type: "button", "aria-label": "Show the whole timeline (0)", "data-testid": "zoom-fit", onclick: () => page.timeline.fit() }, "Fit");
    const zoomIn = h("button", { class: "btn", type: "button", "aria-label": "Zoom in (+)", "data-testid": "zoom-in", onclick: () => zoom(ZOOM_STEP) }, "+");
    return h(
      "div",
      { class: "transport", role: "group", "aria-label": "Playback and view" },
      this.playBtn,
      this.timeEl,
      h("div", { class: "btn-group", role: "group", "aria-label": "Zoom" }, zoomOut, zoomFit, zoomIn),
      this.followBtn,
      this.overlayBtn,
      page.shots.panel.toggleButton(),
      page.lanes.menu,
      keysMenu(),
    );
  }

  /** Follow the player; returns the unsubscribers. */
  wire() {
    const player = this.player;
    return [
      player.on("time", ({ timeS, playing }) => {
        this.showAt(timeS, playing);
        this._keepPlayhead(timeS, playing);
      }),
      player.on("state", ({ playing }) => {
        this.playBtn.textContent = playing ? "❚❚" : "▶";
        this.playBtn.setAttribute("aria-label", playing ? "Pause (Space)" : "Play (Space)");
      }),
      player.on("media-error", ({ message }) => this.page.showNotice(message)),
    ];
  }

  /** Give the video its source (once), and the playhead kept from the last visit once it can seek. */
  attach() {
    if (this.video.getAttribute("src")) return;
    const kept = readLocal(this._playheadKey, 0);
    const restore = () => {
      if (typeof kept === "number" && Number.isFinite(kept) && kept > 0 && this.player.currentTime === 0) this.seek(kept);
      this._keptAt = 0;
    };
    this.video.addEventListener("loadedmetadata", restore, { once: true });
    this.player.on("media-error", restore);  // the wall clock stands in: it seeks at once
    this.video.src = this.page.api.mediaUrl(this.page.projectId);
  }

  get _playheadKey() {
    return `playhead.${this.page.projectId}`;
  }

  /** Keep the playhead for the next visit: each seek or stop, and every second while playing. @param {number} timeS @param {boolean} playing */
  _keepPlayhead(timeS, playing) {
    const now = performance.now();
    if (this._keptAt === null || (playing && now - this._keptAt < KEEP_PLAYHEAD_MS)) return;
    this._keptAt = now;
    writeLocal(this._playheadKey, Math.round(timeS * 1000) / 1000);
  }

  /** Move the playhead and show the values at it. @param {number} timeS @param {boolean} playing */
  showAt(timeS, playing) {
    const { timeline, data, chair } = this.page;
    timeline.setPlayhead(timeS, { page: playing });
    this.timeEl.textContent = `${formatTime(timeS)} / ${formatTime(timeline.durationS)}`;
    const tick = data ? data.tickAt(timeS) : -1;
    chair.showDiagram(timeS, this.lastTick === -1);
    this.page.laneText.update(tick, playing);
    if (data && tick === this.lastTick) return;
    this.lastTick = tick;
    const v = data ? data.valuesAt(tick) : null;
    this.fanOverlay.update(v ? v.fan_grid : null);
  }

  /** Show the values at the playhead again (new data, or the overlay toggled). */
  refresh() {
    this.lastTick = -1;
    const data = this.page.data;
    this.fanOverlay.setBox(data && data.header ? data.header.picture : null);
    this.showAt(this.player.currentTime, this.player.playing);
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
    this.page.timeline.reveal(this.player.currentTime);
  }

  /** @param {boolean} on */
  setOverlay(on) {
    this.fanOverlay.setVisible(on);
    this.overlayBtn.setAttribute("aria-pressed", String(on));
    this.refresh();
    this.page.view.scheduleSave();
  }

  /** @param {boolean} on */
  setFollow(on) {
    this.page.timeline.follow = on;
    this.followBtn.setAttribute("aria-pressed", String(on));
    this.page.view.scheduleSave();
  }

  destroy() {
    if (this.player) this.player.destroy();
    if (this.fanOverlay) this.fanOverlay.destroy();
  }
}
