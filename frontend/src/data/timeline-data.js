/**
 * The composed timeline as the editor holds it: typed arrays straight from /timeline.bin plus
 * min/max pyramids per drawn curve. Read-only; a new instance replaces it after every change.
 *
 * The fan grid (the `fans` block, 153 bytes a tick: 11 MB for two hours) may come after the rest
 * (`?blocks=`): the lanes only draw `fan_activity`; the grid is for the overlay and copying.
 * `withFans()` returns the same timeline with it. Built with the timeline it replaces, it keeps
 * that one's pyramids for the curves whose samples did not change (a threshold commit changes the
 * vibration, not the temperature, fans or features): only the changed lanes are rebuilt. An answer
 * to `?since=` (the revision it replaces) holds only the changed blocks and takes the others,
 * named in its header's `unchanged`, from that timeline.
 */

/** The blocks of the first request: everything but the fan grid. */
export const FIRST_BLOCKS = "vibration,temperature_c,fan_activity,features";

import { parseTimelineBin } from "./binary.js";
import { MinMaxPyramid, channel } from "./pyramid.js";

/**
 * @typedef {{vibration: number[], temperature_c: number, fans: number, fan_grid: Float32Array,
 *   features: Record<string, number>}} TickValues
 * @typedef {Pick<import("./layout.js").ChairLayout, "actuatorIds"|"fanRows"|"fanCols">} GridShape
 */

export class TimelineData {
  /**
   * @param {import("./binary.js").ParsedBin} parsed
   * @param {GridShape} shape the chair's actuators and fan grid (data/layout.js)
   * @param {TimelineData|null} [previous] the timeline this one replaces (its unchanged pyramids are kept)
   */
  constructor(parsed, shape, previous = null) {
    const { header } = parsed;
    const blocks = withUnchanged(parsed, previous);
    /** the blocks as parsed (those kept from `previous` included) */
    this.blocks = blocks;
    this.shape = shape;
    const nAct = shape.actuatorIds.length;
    const n = header.n_ticks;
    if (!Number.isInteger(n) || n < 1) throw new Error(`binary timeline has n_ticks=${n}`);
    this.nTicks = n;
    this.tickS = Number(header.tick_s) || 0.1;
    this.revision = Number(header.revision ?? 0);
    this.header = header;
    const need = (/** @type {string} */ name) => {
      const b = blocks.get(name);
      if (!b) throw new Error(`binary timeline has no "${name}" block`);
      return b;
    };
    const vib = need("vibration");
    checkShape(vib.info, [n, nAct]);
    /** @type {Uint8Array} (n, actuators) bytes, value = byte / 255 */
    this.vibration = /** @type {Uint8Array} */ (vib.data);
    const temp = need("temperature_c");
    checkShape(temp.info, [n]);
    /** @type {Float32Array} */
    this.temperature = /** @type {Float32Array} */ (temp.data);
    /** @type {Uint8Array|null} (n, rows, cols) bytes; null until the `fans` block is loaded */
    this.fans = null;
    const fans = blocks.get("fans");
    if (fans) this.fans = fansOf(fans, n, shape);
    const act = need("fan_activity");
    checkShape(act.info, [n]);
    /** @type {Uint8Array} fraction of fans on x 255 */
    this.fanActivity = /** @type {Uint8Array} */ (act.data);
    /** @type {Map<string, Uint8Array>} */
    this.features = new Map();
    for (const [name, b] of blocks) {
      if (name.startsWith("features.") && b.data instanceof Uint8Array) this.features.set(name.slice(9), b.data);
    }

    /** how many curves' pyramids this timeline built (the others were kept from `previous`) */
    this.pyramidsBuilt = 0;
    const pyramid = (/** @type {any} */ samples, /** @type {MinMaxPyramid|undefined} */ before) => {
      if (before && sameSamples(before.levels[0].min, samples)) return before;
      this.pyramidsBuilt += 1;
      return new MinMaxPyramid(samples);
    };
    /** @type {MinMaxPyramid[]} */
    this.vibrationPyr = shape.actuatorIds.map((_, i) =>
      pyramid(channel(this.vibration, n, nAct, i), previous?.vibrationPyr[i]));
    this.temperaturePyr = pyramid(this.temperature, previous?.temperaturePyr);
    this.fanActivityPyr = pyramid(this.fanActivity, previous?.fanActivityPyr);
    /** @type {Map<string, MinMaxPyramid>} */
    this.featurePyr = new Map();
    for (const [name, data] of this.features) this.featurePyr.set(name, pyramid(data, previous?.featurePyr.get(name)));
    let tmin = Infinity;
    let tmax = -Infinity;
    for (let i = 0; i < n; i++) {
      const v = this.temperature[i];
      if (v < tmin) tmin = v;
      if (v > tmax) tmax = v;
    }
    this.temperatureMin = tmin;
    this.temperatureMax = tmax;
  }

  /** @param {ArrayBuffer} buf @param {GridShape} shape @param {TimelineData|null} [previous] */
  static fromBuffer(buf, shape, previous = null) {
    return new TimelineData(parseTimelineBin(buf), shape, previous);
  }

  /** The fan grid is here (or not yet). */
  get hasFans() {
    return this.fans !== null;
  }

  /**
   * This timeline with the fan grid of a `?blocks=fans` response of the same revision.
   * @param {ArrayBuffer} buf
   */
  withFans(buf) {
    const { header, blocks } = parseTimelineBin(buf);
    if (Number(header.revision) !== this.revision || header.n_ticks !== this.nTicks) {
      throw new Error(`the fan grid is of revision ${header.revision}, the timeline of ${this.revision}`);
    }
    const b = blocks.get("fans");
    if (!b) throw new Error('binary timeline has no "fans" block');
    const copy = Object.assign(Object.create(TimelineData.prototype), this);
    copy.fans = fansOf(b, this.nTicks, this.shape);
    copy.blocks = new Map(this.blocks).set("fans", b);
    return /** @type {TimelineData} */ (copy);
  }

  get durationS() {
    return this.nTicks * this.tickS;
  }

  /** @param {number} timeS @returns {number} the tick under `timeS`, clamped to the timeline */
  tickAt(timeS) {
    return Math.min(this.nTicks - 1, Math.max(0, Math.floor(timeS / this.tickS + 1e-9)));
  }

  /**
   * Every value at one tick (what the chair diagram and the fan overlay show).
   * @param {number} tick
   * @returns {TickValues}
   */
  valuesAt(tick) {
    const k = Math.min(this.nTicks - 1, Math.max(0, Math.floor(tick)));
    const nAct = this.shape.actuatorIds.length;
    const vibration = [];
    for (let i = 0; i < nAct; i++) vibration.push(this.vibration[k * nAct + i] / 255);
    const cells = this.shape.fanRows * this.shape.fanCols;
    const grid = new Float32Array(cells);
    const fans = this.fans;
    if (fans) for (let i = 0; i < cells; i++) grid[i] = fans[k * cells + i] / 255;
    /** @type {Record<string, number>} */
    const features = {};
    for (const [name, data] of this.features) features[name] = data[k] / 255;
    return {
      vibration,
      temperature_c: this.temperature[k],
      fans: this.fanActivity[k] / 255,
      fan_grid: grid,
      features,
    };
  }
}

/**
 * @param {{info: import("./binary.js").BlockInfo, data: any}} block
 * @param {number} n
 * @param {GridShape} shape
 * @returns {Uint8Array}
 */
function fansOf(block, n, shape) {
  checkShape(block.info, [n, shape.fanRows, shape.fanCols]);
  return /** @type {Uint8Array} */ (block.data);
}

/**
 * The parsed blocks plus, for an answer to `?since=`, the blocks its header names `unchanged`
 * taken from `previous` (which must be that revision).
 * @param {import("./binary.js").ParsedBin} parsed
 * @param {TimelineData|null} previous
 */
function withUnchanged(parsed, previous) {
  const { header, blocks } = parsed;
  if (header.since === undefined || header.since === null) return blocks;
  if (!previous || previous.revision !== Number(header.since) || previous.nTicks !== header.n_ticks) {
    throw new Error(`the timeline's changes are since revision ${header.since}, not the one held`);
  }
  const all = new Map(blocks);
  for (const name of header.unchanged || []) {
    const b = previous.blocks.get(name);
    if (b) all.set(name, b);
  }
  return all;
}

/** Same length and values. @param {ArrayLike<number>} a @param {ArrayLike<number>} b */
function sameSamples(a, b) {
  if (a === b) return true;
  if (a.length !== b.length || a.constructor !== b.constructor) return false;
  for (let i = 0; i < a.length; i++) if (a[i] !== b[i]) return false;
  return true;
}

/**
 * @param {import("./binary.js").BlockInfo} info
 * @param {number[]} shape
 */
function checkShape(info, shape) {
  if (info.shape.length !== shape.length || info.shape.some((v, i) => v !== shape[i])) {
    throw new Error(`binary timeline block ${info.name} has shape [${info.shape}], expected [${shape}]`);
  }
}
