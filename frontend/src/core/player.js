/**
 * Playback: the <video> element is the clock. While playing, one frame-loop callback per
 * animation frame reads video.currentTime (timeupdate fires only a few times per second, too rarely
 * for a 100 ms grid) and reports it. When the browser cannot play the media (an unsupported codec),
 * a wall clock stands in so the timeline can still be played through.
 *
 * `sync` events say what the picture does, for followers such as the chair: "play" once frames
 * actually advance (the video's `playing`, not `play`, which comes before any data), "pause" when
 * it pauses, ends or stalls waiting for data, "seek" when a seek completed.
 */

import { Emitter } from "./events.js";

/**
 * @typedef {{
 *   time: {timeS: number, playing: boolean},
 *   state: {playing: boolean},
 *   "media-error": {message: string},
 *   sync: {state: "play"|"pause"|"seek", timeS: number},
 * }} PlayerEvents
 */

/** @extends {Emitter<PlayerEvents>} */
export class Player extends Emitter {
  /**
   * @param {HTMLVideoElement} video
   * @param {{durationS: number, frameLoop: import("./frameloop.js").FrameLoop}} opts
   */
  constructor(video, { durationS, frameLoop }) {
    super();
    this.video = video;
    this.durationS = durationS;
    this.loop = frameLoop;
    this.mediaOk = true;
    /** @type {null|(() => void)} */
    this._stopFrames = null;
    /** wall-clock fallback: time at `_clockStart` */
    this._clockBase = 0;
    this._clockStart = 0;
    this._clockPlaying = false;
    this._clockTime = 0;
    video.addEventListener("play", () => this._started());
    video.addEventListener("pause", () => this._stopped());
    video.addEventListener("ended", () => this._stopped());
    video.addEventListener("seeked", () => {
      if (!this.playing) this.emit("time", { timeS: this.currentTime, playing: false });
      this._sync("seek");
    });
    video.addEventListener("playing", () => this._sync("play"));
    video.addEventListener("pause", () => this._sync("pause"));
    video.addEventListener("waiting", () => {
      if (!video.paused) this._sync("pause");
    });
    video.addEventListener("error", () => {
      this.mediaOk = false;
      const err = video.error;
      this.emit("media-error", {
        message: `The browser cannot play this video${err && err.message ? ` (${err.message})` : ""}; the timeline plays without picture.`,
      });
    });
  }

  get playing() {
    return this.mediaOk ? !this.video.paused && !this.video.ended : this._clockPlaying;
  }

  /** Seconds from the start. */
  get currentTime() {
    if (this.mediaOk) return this.video.currentTime;
    if (!this._clockPlaying) return this._clockTime;
    return Math.min(this.durationS, this._clockBase + (performance.now() - this._clockStart) / 1000);
  }

  async play() {
    if (this.playing) return;
    if (this.mediaOk) {
      await this.video.play();
      return;
    }
    this._clockBase = this._clockTime >= this.durationS ? 0 : this._clockTime;
    this._clockStart = performance.now();
    this._clockPlaying = true;
    this._started();
    this._sync("play");
  }

  pause() {
    if (this.mediaOk) this.video.pause();
    else if (this._clockPlaying) {
      this._clockTime = this.currentTime;
      this._clockPlaying = false;
      this._stopped();
      this._sync("pause");
    }
  }

  toggle() {
    return this.playing ? (this.pause(), Promise.resolve()) : this.play();
  }

  /** @param {number} timeS */
  seek(timeS) {
    const t = Math.min(this.durationS, Math.max(0, timeS));
    if (this.mediaOk) {
      this.video.currentTime = t;
    } else {
      this._clockTime = t;
      this._clockBase = t;
      this._clockStart = performance.now();
      this._sync("seek");
    }
    this.emit("time", { timeS: t, playing: this.playing });
  }

  /** @param {"play"|"pause"|"seek"} state */
  _sync(state) {
    this.emit("sync", { state, timeS: this.currentTime });
  }

  _started() {
    if (!this._stopFrames) {
      this._stopFrames = this.loop.add(() => {
        const t = this.currentTime;
        if (!this.mediaOk && t >= this.durationS) this.pause();
        this.emit("time", { timeS: t, playing: this.playing });
      });
    }
    this.emit("state", { playing: true });
  }

  _stopped() {
    if (this._stopFrames) {
      this._stopFrames();
      this._stopFrames = null;
    }
    this.emit("time", { timeS: this.currentTime, playing: false });
    this.emit("state", { playing: false });
  }

  destroy() {
    if (this._stopFrames) this._stopFrames();
    this.video.pause();
    this.video.removeAttribute("src");
    this.video.load();
    this.clearListeners();
  }
}
