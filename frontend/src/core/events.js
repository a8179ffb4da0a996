/**
 * A typed event emitter (wavesurfer.js style): `on()` returns its own unsubscribe function.
 *
 * The event map is a JSDoc type parameter, so `tsc --checkJs` checks event names and payloads:
 *
 *   /** @extends {Emitter<{seek: {time_s: number}}>} *\/
 *   class Player extends Emitter {}
 *   const off = player.on("seek", (e) => console.log(e.time_s));
 *   off();
 *
 * @template {Record<string, any>} M
 */
export class Emitter {
  constructor() {
    /** @type {Map<keyof M, Set<(payload: any) => void>>} */
    this._handlers = new Map();
  }

  /**
   * Subscribe to `type`; returns the function that unsubscribes.
   * @template {keyof M} K
   * @param {K} type
   * @param {(payload: M[K]) => void} fn
   * @returns {() => void}
   */
  on(type, fn) {
    let set = this._handlers.get(type);
    if (!set) {
      set = new Set();
      this._handlers.set(type, set);
    }
    set.add(fn);
    return () => {
      set.delete(fn);
    };
  }

  /**
   * @template {keyof M} K
   * @param {K} type
   * @param {M[K]} payload
   */
  emit(type, payload) {
    const set = this._handlers.get(type);
    if (!set) return;
    for (const fn of [...set]) fn(payload);
  }

  /** Drop every subscription (when the owner is destroyed). */
  clearListeners() {
    this._handlers.clear();
  }
}
