/**
 * The chair as the server describes it in GET /api/config: the actuators with their places and
 * zones, the size of the fan grid, the temperature range, the lanes an edit can address, and the
 * tick. The frontend declares none of these itself; every module reads them from here.
 */

/**
 * @typedef {{id: string, x: number, y: number, zone: string, body?: string}} ActuatorInfo
 * @typedef {{lo: number, hi: number, neutral: number}} TemperatureRange degrees C
 * @typedef {{
 *   actuators: ActuatorInfo[],
 *   actuatorIds: string[],
 *   fanRows: number,
 *   fanCols: number,
 *   temperature: TemperatureRange,
 *   editLanes: string[],
 *   features: string[],
 *   tickS: number,
 * }} ChairLayout
 */

/**
 * Read the layout out of /api/config; a field the editor cannot do without is an error that names it.
 * @param {Record<string, any>} config
 * @returns {ChairLayout}
 */
export function chairLayout(config) {
  const layout = field(config, "layout", "object");
  const actuators = field(layout, "actuators", "array").map((/** @type {any} */ a) => ({
    id: String(a.id), x: Number(a.x), y: Number(a.y), zone: String(a.zone), body: a.body ? String(a.body) : undefined,
  }));
  const fans = field(layout, "fans", "object");
  const t = field(config, "temperature", "object");
  return Object.freeze({
    actuators,
    actuatorIds: actuators.map((a) => a.id),
    fanRows: field(fans, "rows", "number"),
    fanCols: field(fans, "cols", "number"),
    temperature: { lo: field(t, "low_c", "number"), hi: field(t, "high_c", "number"), neutral: field(t, "neutral_c", "number") },
    editLanes: field(config, "lanes", "array").map(String),
    features: field(config, "features", "array").map(String),
    tickS: field(config, "tick_s", "number"),
  });
}

/**
 * The temperature range to draw: the generator's range, widened to the values a timeline holds
 * and to the curve the chair plays.
 * @param {TemperatureRange} range
 * @param {{temperatureMin: number, temperatureMax: number}|null} data
 * @param {{lo: number, hi: number}|null} [played]
 * @returns {TemperatureRange}
 */
export function drawnTemperatureRange(range, data, played = null) {
  const lo = Math.min(range.lo, data ? data.temperatureMin : Infinity, played ? played.lo : Infinity);
  const hi = Math.max(range.hi, data ? data.temperatureMax : -Infinity, played ? played.hi : -Infinity);
  return { lo, hi, neutral: range.neutral };
}

/**
 * @param {Record<string, any>} obj
 * @param {string} name
 * @param {"object"|"array"|"number"} kind
 */
function field(obj, name, kind) {
  const v = obj[name];
  const ok = kind === "array" ? Array.isArray(v) && v.length > 0 : kind === "number" ? Number.isFinite(v) : !!v && typeof v === "object";
  if (!ok) throw new Error(`/api/config has no usable "${name}" (expected ${kind === "array" ? "a non-empty array" : `a ${kind}`})`);
  return v;
}
