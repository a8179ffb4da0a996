/**
 * Colours shared by the lanes, the chair diagram and the fan overlay (dark theme).
 */

export const COLORS = {
  laneBg: "#12151c",
  grid: "#232836",
  text: "#8b93a7",
  waveform: "#5eead4",
  feature: "#38bdf8",
  featureDim: "rgba(56, 189, 248, 0.28)",
  featureHot: "#fbbf24",
  threshold: "#f472b6",
  vibration: "#fb923c",
  tempLine: "#f87171",
  tempNeutral: "#64748b",
  tempTarget: "rgba(148, 163, 184, 0.55)",
  tempLimit: "#fb923c",
  fans: "#67e8f9",
  marker: "#facc15",
  draft: "#e879f9",
};

/** Heat map stops (value 0 is the lane background, so silence reads as dark). */
const HEAT_STOPS = [
  [0.0, [18, 21, 28]],
  [0.08, [40, 24, 82]],
  [0.35, [123, 35, 130]],
  [0.6, [212, 70, 58]],
  [0.82, [248, 154, 44]],
  [1.0, [252, 245, 168]],
];

/** 256 colours packed as little-endian RGBA words for ImageData (byte -> colour). */
export const HEAT_LUT = buildLut(HEAT_STOPS);

/** @param {number} v 0..1 @returns {string} CSS colour of the heat map */
export function heatColor(v) {
  const i = Math.max(0, Math.min(255, Math.round(v * 255)));
  const w = HEAT_LUT[i];
  return `rgb(${w & 255}, ${(w >>> 8) & 255}, ${(w >>> 16) & 255})`;
}

/**
 * Temperature colour: blue below the neutral value, grey at it, red above.
 * @param {number} c degrees C
 * @param {number} neutral
 * @param {number} lo
 * @param {number} hi
 */
export function temperatureColor(c, neutral, lo, hi) {
  if (c >= neutral) {
    const f = Math.min(1, (c - neutral) / Math.max(1e-6, hi - neutral));
    return mix([148, 163, 184], [248, 113, 113], f);
  }
  const f = Math.min(1, (neutral - c) / Math.max(1e-6, neutral - lo));
  return mix([148, 163, 184], [96, 165, 250], f);
}

/**
 * @param {number[]} a
 * @param {number[]} b
 * @param {number} f
 */
function mix(a, b, f) {
  const c = a.map((v, i) => Math.round(v + (b[i] - v) * f));
  return `rgb(${c[0]}, ${c[1]}, ${c[2]})`;
}

/** @param {Array<[number, number[]]>|any[]} stops */
function buildLut(stops) {
  const lut = new Uint32Array(256);
  for (let i = 0; i < 256; i++) {
    const v = i / 255;
    let k = 0;
    while (k < stops.length - 2 && v > stops[k + 1][0]) k++;
    const [v0, c0] = stops[k];
    const [v1, c1] = stops[k + 1];
    const f = Math.min(1, Math.max(0, (v - v0) / (v1 - v0)));
    const r = Math.round(c0[0] + (c1[0] - c0[0]) * f);
    const g = Math.round(c0[1] + (c1[1] - c0[1]) * f);
    const b = Math.round(c0[2] + (c1[2] - c0[2]) * f);
    lut[i] = (255 << 24) | (b << 16) | (g << 8) | r;
  }
  return lut;
}
