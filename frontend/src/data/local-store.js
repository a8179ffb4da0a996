/**
 * What this browser keeps for the user between visits (localStorage, JSON): view preferences
 * that are not the project's (lane heights, the playhead). A browser that refuses storage (private
 * mode, quota) simply keeps nothing.
 */

const PREFIX = "autohaptics.";

/**
 * The value stored under `key`, or `fallback` when there is none or it is unreadable.
 * @template T
 * @param {string} key
 * @param {T} fallback
 * @returns {T}
 */
export function readLocal(key, fallback) {
  try {
    const raw = window.localStorage.getItem(PREFIX + key);
    return raw === null ? fallback : JSON.parse(raw);
  } catch {
    return fallback;
  }
}

/** Store a JSON value under `key` (nothing when the browser refuses). @param {string} key @param {unknown} value */
export function writeLocal(key, value) {
  try {
    window.localStorage.setItem(PREFIX + key, JSON.stringify(value));
  } catch {
    // storage refused: the preference lasts until the page closes
  }
}
