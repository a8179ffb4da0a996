/**
 * A project's shots as GET /api/projects/{id}/shots gives them (docs/API.md "Shots"): ticks
 * [t0, t1) tiling the film in order, each with its summary. Lookups by tick are binary searches
 * over the starts, so drawing a 2,000-shot film touches only the shots on screen. The Shots
 * panel's orders and filters live here too (pure functions of the list).
 */

/**
 * @typedef {{id: number, t0: number, t1: number, kind: string, vibration_mean: number|null,
 *   vibration_peak: number|null, temperature_mean_c: number|null, fans_share: number|null,
 *   loudness_sone: number|null, colour: string|null, motion: number|null, poster_url: string}} Shot
 */

export class ShotList {
  /** @param {{revision: number, n_ticks: number, tick_s: number, shots: Shot[]}} doc */
  constructor(doc) {
    this.revision = doc.revision;
    this.nTicks = doc.n_ticks;
    this.tickS = doc.tick_s;
    /** @type {Shot[]} */
    this.shots = doc.shots;
    this.starts = Int32Array.from(doc.shots, (s) => s.t0);
    /** @type {Map<number, number>} shot id -> index */
    this.byId = new Map(doc.shots.map((s, i) => [s.id, i]));
  }

  get length() {
    return this.shots.length;
  }

  /** Index of the shot holding `tick` (clamped to the film), -1 for an empty list. @param {number} tick */
  indexAt(tick) {
    const s = this.starts;
    if (!s.length) return -1;
    let lo = 0;
    let hi = s.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (s[mid] <= tick) lo = mid;
      else hi = mid - 1;
    }
    return lo;
  }

  /** @param {number} tick @returns {Shot|null} */
  at(tick) {
    const i = this.indexAt(tick);
    return i < 0 ? null : this.shots[i];
  }

  /** @param {number} id @returns {Shot|null} */
  get(id) {
    const i = this.byId.get(id);
    return i === undefined ? null : this.shots[i];
  }

  /**
   * The boundary tick (a shot's start after the first, or the film's end) nearest to `tick`
   * within `tolTicks`, else null.
   * @param {number} tick @param {number} tolTicks
   */
  boundaryNear(tick, tolTicks) {
    if (!this.starts.length) return null;
    const i = this.indexAt(tick);
    /** @type {number[]} */
    const cands = [this.starts[i], i + 1 < this.starts.length ? this.starts[i + 1] : this.nTicks];
    let best = null;
    let bestD = tolTicks;
    for (const b of cands) {
      const d = Math.abs(b - tick);
      if (d <= bestD) {
        best = b;
        bestD = d;
      }
    }
    return best;
  }
}

/** Orders of the Shots panel: [id, label, key (larger first unless `asc`)]. */
export const SHOT_SORTS = /** @type {Array<{id: string, label: string, key: (s: Shot) => number, asc?: boolean}>} */ ([
  { id: "time", label: "In film order", key: (s) => s.t0, asc: true },
  { id: "loudest", label: "Loudest", key: (s) => s.loudness_sone ?? -1 },
  { id: "fans", label: "Most fans", key: (s) => s.fans_share ?? -1 },
  { id: "warmest", label: "Warmest", key: (s) => s.temperature_mean_c ?? -1e9 },
  { id: "coolest", label: "Coolest", key: (s) => -(s.temperature_mean_c ?? 1e9) },
  { id: "vibration", label: "Strongest vibration", key: (s) => s.vibration_mean ?? -1 },
  { id: "motion", label: "Most motion", key: (s) => s.motion ?? -1 },
  { id: "longest", label: "Longest", key: (s) => s.t1 - s.t0 },
]);

/** Filters of the Shots panel. */
export const SHOT_FILTERS = /** @type {Array<{id: string, label: string, keep: (s: Shot) => boolean}>} */ ([
  { id: "all", label: "All shots", keep: () => true },
  { id: "fans", label: "With fans on", keep: (s) => (s.fans_share ?? 0) > 0 },
  { id: "vibration", label: "Vibrating", keep: (s) => (s.vibration_peak ?? 0) > 0 },
  { id: "still", label: "No effects", keep: (s) => !(s.vibration_peak ?? 0) && !(s.fans_share ?? 0) },
  { id: "fades", label: "Begins with a fade or dissolve", keep: (s) => s.kind === "fade" || s.kind === "dissolve" },
  { id: "split", label: "Split by hand", keep: (s) => s.kind === "split" },
]);

/**
 * The shots a panel shows: filtered, then ordered (ties in film order).
 * @param {Shot[]} shots @param {string} sortId @param {string} filterId
 */
export function arrangeShots(shots, sortId, filterId) {
  const sort = SHOT_SORTS.find((s) => s.id === sortId) || SHOT_SORTS[0];
  const filter = SHOT_FILTERS.find((f) => f.id === filterId) || SHOT_FILTERS[0];
  const kept = shots.filter(filter.keep);
  const sign = sort.asc ? 1 : -1;
  return kept.sort((a, b) => sign * (sort.key(a) - sort.key(b)) || a.t0 - b.t0);
}

/**
 * The shots whose distance to the chosen one is at most `maxDistance` (the similar route's answer).
 * @param {Array<{id: number, distance: number}>} similar ascending distance
 * @param {number} maxDistance 0..1
 */
export function similarWithin(similar, maxDistance) {
  const out = [];
  for (const s of similar) {
    if (s.distance > maxDistance) break;
    out.push(s.id);
  }
  return out;
}
