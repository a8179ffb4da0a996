/**
 * The lanes in words, for assistive tech: the lanes are drawn on canvases, so each lane's canvas
 * is described (aria-describedby) by a visually hidden line saying what the lane holds at the
 * playhead and within WINDOW_S of it (values, thresholds, what the chair plays, markers).
 * Updated when the playhead moves to another tick (at most once a second while playing) and
 * when a new timeline is shown.
 */

import { h } from "../../core/dom.js";
import { formatTime } from "../../data/format.js";

/** Seconds either side of the playhead that each line sums up. */
export const WINDOW_S = 2;
const PLAYING_EVERY_MS = 1000;

/** @typedef {import("../../data/timeline-data.js").TimelineData} TimelineData */

export class LaneText {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {Map<string, HTMLElement>} lane id -> its hidden description */
    this.lines = new Map();
    this._at = 0;
  }

  /** Give every lane of the timeline its description. @param {import("../../core/timeline.js").TimelineView} tl */
  attach(tl) {
    for (const { lane, row, canvas } of tl.lanes) {
      const id = `lane-text-${lane.id}`;
      const line = h("p", { class: "visually-hidden", id, "data-testid": id });
      row.append(line);
      canvas.setAttribute("aria-describedby", id);
      this.lines.set(lane.id, line);
    }
  }

  /** Describe the lanes again at the player's position (new markers, the chair's curve loaded). */
  refresh() {
    const data = this.page.data;
    this._at = 0;
    this.update(data ? data.tickAt(this.page.media.player.currentTime) : -1, false);
  }

  /** Describe the lanes around `tick` (-1: no timeline). @param {number} tick @param {boolean} playing */
  update(tick, playing) {
    const now = performance.now();
    if (playing && now - this._at < PLAYING_EVERY_MS) return;
    this._at = now;
    const data = this.page.data;
    for (const [id, line] of this.lines) {
      const text = data && tick >= 0 ? this._describe(id, data, tick) : "No timeline yet.";
      if (line.textContent !== text) line.textContent = text;
    }
  }

  /** @param {string} id @param {TimelineData} data @param {number} tick */
  _describe(id, data, tick) {
    const page = this.page;
    const w = Math.round(WINDOW_S / data.tickS);
    const t0 = Math.max(0, tick - w);
    const t1 = Math.min(data.nTicks, tick + w + 1);
    const at = `At ${formatTime(tick * data.tickS)}`;
    const around = `${formatTime(t0 * data.tickS)}–${formatTime(t1 * data.tickS)}`;
    const ids = page.layout.actuatorIds;
    if (id.startsWith("feature-")) {
      const name = id.slice("feature-".length);
      const values = data.features.get(name);
      if (!values) return "Not computed for this project.";
      const thr = page.params.thresholds[name];
      const [lo, hi] = span(values, t0, t1, 1, 0, 1 / 255);
      return `${at}: ${(values[tick] / 255).toFixed(2)}${typeof thr === "number" ? ` (threshold ${thr.toFixed(2)})` : ""}; ${around}: ${lo.toFixed(2)} to ${hi.toFixed(2)}.`;
    }
    if (id === "actuators") {
      const now = ids.map((a, i) => `${a} ${(data.vibration[tick * ids.length + i] / 255).toFixed(2)}`).join(", ");
      let best = { v: -1, a: "", k: 0 };
      for (let k = t0; k < t1; k++) ids.forEach((a, i) => {
        const v = data.vibration[k * ids.length + i] / 255;
        if (v > best.v) best = { v, a, k };
      });
      return `${at}: ${now}; strongest ${around}: ${best.a} ${best.v.toFixed(2)} at ${formatTime(best.k * data.tickS)}.`;
    }
    if (id === "detail") {
      const a = page.lanes.detail.actuator;
      const i = Math.max(0, ids.indexOf(a));
      const [lo, hi] = span(data.vibration, t0, t1, ids.length, i, 1 / 255);
      return `${a} ${at.toLowerCase()}: ${(data.vibration[tick * ids.length + i] / 255).toFixed(2)}; ${around}: ${lo.toFixed(2)} to ${hi.toFixed(2)}.`;
    }
    if (id === "temperature") return this._temperature(data, tick, t0, t1, at, around);
    if (id === "fans") {
      const [, hi] = span(data.fanActivity, t0, t1, 1, 0, 100 / 255);
      return `${at}: ${Math.round((data.fanActivity[tick] * 100) / 255)} % of the fans on; ${around}: up to ${Math.round(hi)} %.`;
    }
    if (id === "markers") {
      const near = page.markers.list.filter((m) => m.t_s >= t0 * data.tickS && m.t_s < t1 * data.tickS);
      const all = page.markers.list.length;
      if (!near.length) return `No marker ${around}; ${all} in all.`;
      return `Markers ${around}: ${near.map((m) => `"${m.label}" at ${formatTime(m.t_s)}`).join(", ")}; ${all} in all.`;
    }
    return "The film's sound as a waveform.";
  }

  /** @param {TimelineData} data @param {number} tick @param {number} t0 @param {number} t1 @param {string} at @param {string} around */
  _temperature(data, tick, t0, t1, at, around) {
    const played = this.page.played && this.page.played.revision === data.revision ? this.page.played : null;
    const target = `target ${data.temperature[tick].toFixed(1)} °C`;
    const chair = played ? `, the chair plays ${played.at(tick).toFixed(1)} °C (its limits ${played.minC.toFixed(1)} to ${played.maxC.toFixed(1)} °C)` : "";
    const [lo, hi] = span(played ? played.values : data.temperature, t0, t1, 1, 0, 1);
    return `${at}: ${target}${chair}; ${around}: ${played ? "the chair plays" : "target"} ${lo.toFixed(1)} to ${hi.toFixed(1)} °C.`;
  }
}

/**
 * Smallest and largest of column `col` of a row-major array over rows [t0, t1), times `scale`.
 * @param {ArrayLike<number>} values @param {number} t0 @param {number} t1 @param {number} stride @param {number} col @param {number} scale
 * @returns {[number, number]}
 */
function span(values, t0, t1, stride, col, scale) {
  let lo = Infinity;
  let hi = -Infinity;
  for (let k = t0; k < t1; k++) {
    const v = values[k * stride + col];
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  return [lo * scale, hi * scale];
}
