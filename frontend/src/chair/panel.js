/**
 * The chair panel: port picker, connect / disconnect, the live status (GET /api/chair/events),
 * latency offset, comfort (intensity, zone mutes) and pushing a range. Connection status is
 * neither saved nor undoable; latency and comfort are the server's chair settings (stored there).
 */

import { errorText } from "../data/http.js";
import { Emitter } from "../core/events.js";
import { h } from "../core/dom.js";
import { progressBar, toast } from "../panels/widgets.js";
import { formatTime } from "../data/format.js";

export const LATENCY_RANGE_MS = [-500, 500];
const ZONES = /** @type {const} */ ([
  ["back", "Back"],
  ["armrests", "Armrests"],
  ["seat", "Seat"],
  ["heat", "Heat"],
  ["fans", "Fans"],
]);
const STATE_TEXT = /** @type {Record<string, string>} */ ({
  idle: "Not connected",
  connected: "Connected",
  reconnecting: "Reconnecting…",
  disconnected: "Disconnected",
  closed: "Not connected",
});

/**
 * @typedef {import("../data/api.js").ChairStatus} ChairStatus
 * @typedef {{status: ChairStatus, active: boolean}} ChairPanelEvents
 */

/** @extends {Emitter<{status: ChairPanelEvents}>} */
export class ChairPanel extends Emitter {
  /**
   * @param {import("../data/api.js").Api} api
   * @param {{projectId: string, tickS: number, range: () => {startS: number, endS: number, label: string}}} opts
   */
  constructor(api, { projectId, tickS, range }) {
    super();
    this.api = api;
    this.projectId = projectId;
    this.tickS = tickS;
    this.range = range;
    this.portSelect = h("select", { class: "input chair-port", id: "chair-port", "data-testid": "chair-port" });
    /** @type {string|null} the port the user picked in the list (none: the list defaults to a chair-like one) */
    this.chosenPort = null;
    this.portSelect.addEventListener("change", () => {
      this.chosenPort = this.portSelect.value || null;
    });
    this.refreshBtn = h("button", { class: "btn btn-small", type: "button", "aria-label": "Refresh the port list", title: "Refresh the port list", "data-testid": "chair-refresh", onclick: () => this.refreshPorts() }, "↻");
    this.connectBtn = h("button", { class: "btn btn-small btn-primary", type: "button", "data-testid": "chair-connect", onclick: () => this.toggleConnection() }, "Connect");
    this.stateEl = h("span", { class: "badge chair-state", "data-state": "idle", "data-testid": "chair-state" }, STATE_TEXT.idle);
    this.values = {
      port: h("dd", { "data-testid": "chair-status-port" }, "–"),
      frames: h("dd", { "data-testid": "chair-frames" }, "0"),
      lastTick: h("dd", { "data-testid": "chair-last-tick" }, "–"),
      errors: h("dd", { "data-testid": "chair-errors" }, "–"),
      safe: h("dd", { "data-testid": "chair-safe" }, "–"),
      reconnects: h("dd", { "data-testid": "chair-reconnects" }, "0"),
    };
    const rows = /** @type {Array<[string, HTMLElement]>} */ ([
      ["Port", this.values.port],
      ["Frames sent", this.values.frames],
      ["Last tick", this.values.lastTick],
      ["Chair errors", this.values.errors],
      ["Safe state", this.values.safe],
      ["Reconnects", this.values.reconnects],
    ]);
    this.errorEl = h("p", { class: "chair-error", role: "alert", hidden: true, "data-testid": "chair-error" });

    this.latencyInput = h("input", {
      type: "number", class: "input input-num", id: "chair-latency", min: LATENCY_RANGE_MS[0], max: LATENCY_RANGE_MS[1], step: 1,
      value: "0", inputmode: "numeric", "data-testid": "chair-latency", "aria-describedby": "chair-latency-hint",
    });
    this.latencyHint = h("span", { class: "field-hint", id: "chair-latency-hint" }, "ms, −500…500; positive sends earlier");
    this.latencyInput.addEventListener("change", () => this.commitLatency());

    const chips = this._buildComfort();

    this.pushBtn = h("button", { class: "btn btn-small", type: "button", "data-testid": "chair-push", onclick: () => this.pushRange() }, "Push to chair");
    this.pushProgress = progressBar("Push to the chair", "chair-push-progress");
    this.pushProgress.el.hidden = true;
    this.pushText = h("p", { class: "chair-push-text", "data-testid": "chair-push-text", "aria-live": "polite", hidden: true });

    this.el = h(
      "section",
      { class: "panel chair-panel", "aria-labelledby": "chair-panel-title", "data-testid": "chair-panel" },
      h("h2", { class: "panel-title", id: "chair-panel-title" }, "Chair ", this.stateEl),
      h("div", { class: "chair-row" }, h("label", { class: "visually-hidden", for: "chair-port" }, "Chair port"), this.portSelect, this.refreshBtn, this.connectBtn),
      h("dl", { class: "chair-status", "data-testid": "chair-status" }, ...rows.flatMap(([k, v]) => [h("dt", {}, k), v])),
      this.errorEl,
      h("label", { class: "chair-field", for: "chair-latency" }, h("span", {}, "Latency offset"), h("span", { class: "chair-field-input" }, this.latencyInput, this.latencyHint)),
      h("label", { class: "threshold-row", for: "chair-intensity" }, h("span", {}, "Intensity"), this.intensityInput, this.intensityOut),
      chips,
      h("div", { class: "chair-row" }, this.pushBtn, this.pushProgress.el, this.pushText),
    );
    /** @type {ChairStatus|null} */
    this.status = null;
    this.busy = false;
    /** @type {null|(() => void)} */
    this._unwatch = null;
    /** @type {Promise<void>|null} */
    this._settingsChain = null;
    /** Settings changes sent and not yet answered: a status event meanwhile may hold older settings. */
    this._settingsInFlight = 0;
    this._render();
  }

  /** The comfort controls: overall intensity and one mute per zone; returns the mute chips. */
  _buildComfort() {
    this.intensityInput = h("input", { type: "range", class: "range", id: "chair-intensity", min: 0, max: 1, step: 0.05, value: "1", "data-testid": "chair-intensity" });
    this.intensityOut = h("output", { class: "range-value", for: "chair-intensity" }, "1.00");
    this.intensityInput.addEventListener("input", () => {
      this.intensityOut.textContent = Number(this.intensityInput.value).toFixed(2);
    });
    this.intensityInput.addEventListener("change", () => this.putSettings({ comfort: { scale: Number(this.intensityInput.value) } }));

    /** @type {Map<string, HTMLButtonElement>} */
    this.muteBtns = new Map();
    const chips = h("div", { class: "chip-group", role: "group", "aria-label": "Mute zones" });
    for (const [zone, label] of ZONES) {
      const btn = h("button", {
        class: "chip", type: "button", "aria-pressed": "false", "data-testid": `chair-mute-${zone}`,
        title: `Mute ${label.toLowerCase()} on the chair`,
        onclick: () => this.putSettings({ comfort: { mute: { [zone]: btn.getAttribute("aria-pressed") !== "true" } } }),
      }, label);
      this.muteBtns.set(zone, btn);
      chips.append(btn);
    }
    return chips;
  }

  /** The range to push changed (a new selection). */
  updateRange() {
    this._render();
  }

  /** A chair link exists (connected or reconnecting): playback is reported to it. */
  get active() {
    const s = this.status;
    return !!s && (s.state === "connected" || s.state === "reconnecting");
  }

  /** Load the port list and follow the chair's status. */
  open() {
    this.refreshPorts();
    this._unwatch = this.api.watchChair((status) => this._setStatus(status));
  }

  async refreshPorts() {
    let ports;
    try {
      ports = await this.api.chairPorts();
    } catch (err) {
      toast(`Could not list the chair ports: ${errorText(err)}`, "error");
      return;
    }
    // The port in use or picked in the list, else the first that looks like a chair (a virtual chair
    // counts); never the list's implicit first option (/dev/ttyS0 listed before a chair appeared).
    const current = (this.status && this.status.port) || this.chosenPort;
    this.portSelect.replaceChildren(
      ...ports.map((p) => h("option", { value: p.device }, `${p.device}${p.likely_chair ? " ★" : ""}${p.description ? ` — ${p.description}` : ""}`)),
    );
    if (!ports.length) this.portSelect.append(h("option", { value: "" }, "No ports found"));
    const chairLike = ports.find((p) => p.likely_chair) || ports.find((p) => p.kind === "virtual");
    if (current && ports.some((p) => p.device === current)) this.portSelect.value = current;
    else if (chairLike) this.portSelect.value = chairLike.device;
    this._render();
  }

  async toggleConnection() {
    if (this.busy) return;
    this.busy = true;
    this._render();
    try {
      if (this.active) this._setStatus(await this.api.chairDisconnect());
      else {
        const port = this.portSelect.value;
        if (!port) {
          toast("Choose a port first (↻ refreshes the list).", "warn");
          return;
        }
        this._setStatus(await this.api.chairConnect(port));
      }
    } catch (err) {
      this._showError(errorText(err));
    } finally {
      this.busy = false;
      this._render();
    }
  }

  async commitLatency() {
    const raw = this.latencyInput.value.trim();
    const v = Number(raw);
    const [lo, hi] = LATENCY_RANGE_MS;
    if (raw === "" || !Number.isFinite(v) || v < lo || v > hi) {
      this.latencyInput.setAttribute("aria-invalid", "true");
      this.latencyHint.textContent = `Enter a number of milliseconds from ${lo} to ${hi}.`;
      return;
    }
    this.latencyInput.removeAttribute("aria-invalid");
    this.latencyHint.textContent = "ms, −500…500; positive sends earlier";
    await this.putSettings({ latency_ms: v });
  }

  /**
   * Change settings on the server; changes go out one at a time in the order they were made (a
   * slider moved by several key presses ends at its last value).
   * @param {{latency_ms?: number, comfort?: {scale?: number, mute?: Record<string, boolean>}}} change
   */
  putSettings(change) {
    this._settingsInFlight += 1;
    this._settingsChain = (this._settingsChain || Promise.resolve()).then(async () => {
      try {
        const settings = await this.api.putChairSettings(change);
        this._settingsInFlight -= 1;
        if (this.status) this._setStatus({ ...this.status, settings });
      } catch (err) {
        this._settingsInFlight -= 1;
        toast(`The chair settings were not changed: ${errorText(err)}`, "error");
        if (this.status) this._renderSettings(this.status.settings, true);
      }
    });
    return this._settingsChain;
  }

  async pushRange() {
    const { startS, endS, label } = this.range();
    try {
      this._setStatus(await this.api.chairPush(this.projectId, startS, endS));
      toast(`Pushing ${label} to the chair.`);
    } catch (err) {
      this._showError(errorText(err));
    }
  }

  /** STOP: every output off now. */
  async stop() {
    try {
      this._setStatus(await this.api.chairStop());
    } catch (err) {
      this._showError(`STOP failed: ${errorText(err)}`);
    }
  }

  /** @param {ChairStatus} status */
  _setStatus(status) {
    this.status = status;
    if (status.port && !Array.from(this.portSelect.options).some((o) => o.value === status.port)) {
      this.portSelect.append(h("option", { value: status.port }, status.port));
    }
    if (status.port) this.portSelect.value = status.port;
    this._render();
    this.emit("status", { status, active: this.active });
  }

  /** @param {string} message */
  _showError(message) {
    this.errorEl.textContent = message;
    this.errorEl.hidden = false;
  }

  _render() {
    const s = this.status;
    const state = s ? s.state : "idle";
    this.stateEl.textContent = STATE_TEXT[state] || state;
    this.stateEl.dataset.state = state;
    this.connectBtn.textContent = this.active ? "Disconnect" : "Connect";
    this.connectBtn.classList.toggle("btn-primary", !this.active);
    this.connectBtn.disabled = this.busy || (!this.active && !this.portSelect.value);
    this.portSelect.disabled = this.busy || this.active;
    this.pushBtn.disabled = !s || !s.connected;
    const { label } = this.range();
    this.pushBtn.textContent = `Push ${label}`;
    if (!s) return;
    const v = this.values;
    v.port.textContent = s.port || "–";
    // The counters are this project's: after another project played, they show "–" here.
    const mine = this.chairPlaysThis;
    v.frames.textContent = mine ? String(s.frames_sent) : "–";
    v.lastTick.textContent = !mine || s.last_tick === null ? "–" : `${s.last_tick} (${formatTime(s.last_tick * this.tickS)})`;
    const chair = s.diagnostics && s.diagnostics.chair;
    v.errors.textContent = chair ? `CRC ${chair.crc_errors} · length ${chair.length_errors}` : "–";
    v.safe.textContent = chair ? (chair.safe ? `yes (${chair.safe_reason})` : "no") : "–";
    v.safe.dataset.safe = chair ? String(!!chair.safe) : "";
    v.reconnects.textContent = String(s.reconnects);
    const error = s.error || (state === "reconnecting" && s.diagnostics ? s.diagnostics.last_error : null);
    this.errorEl.hidden = !error;
    this.errorEl.textContent = error || "";
    this._renderPush(s.push && s.push.project_id === this.projectId ? s.push : null);
    this._renderSettings(s.settings, false);
  }

  /** Whether the chair's counters belong to this project (nothing else played since it connected). */
  get chairPlaysThis() {
    const s = this.status;
    const owner = s && ((s.push && s.push.project_id) || (s.playback && s.playback.project_id));
    return !owner || owner === this.projectId;
  }

  /** Where a running push of this project has the chair (s), else null. */
  get pushPositionS() {
    const s = this.status;
    const push = s && s.push;
    if (!push || push.project_id !== this.projectId || push.state !== "running") return null;
    return s.last_tick === null ? push.start_s : Math.max(push.start_s, Math.min(push.end_s, s.last_tick * this.tickS));
  }

  /** The push's bar and, in words, where the chair is and how far it has got. @param {import("../data/api.js").ChairPush|null} push */
  _renderPush(push) {
    this.pushProgress.el.hidden = this.pushText.hidden = !push;
    if (!push) return;
    const span = `${formatTime(push.start_s)}–${formatTime(push.end_s)}`;
    this.pushProgress.set(push.progress, push.state);
    const at = this.pushPositionS;
    this.pushText.textContent = at !== null
      ? `Chair at ${formatTime(at)} · ${Math.round(push.progress * 100)} % of ${span}`
      : `Push of ${span} ${push.state}${push.error ? `: ${push.error}` : ""}`;
  }

  /**
   * @param {import("../data/api.js").ChairSettings} settings
   * @param {boolean} force also overwrite a field the user is typing in
   */
  _renderSettings(settings, force) {
    if (!settings || (!force && this._settingsInFlight > 0)) return;
    if (force || document.activeElement !== this.latencyInput) {
      this.latencyInput.value = String(settings.latency_ms);
      this.latencyInput.removeAttribute("aria-invalid");
    }
    if (force || document.activeElement !== this.intensityInput) {
      this.intensityInput.value = String(settings.comfort.scale);
      this.intensityOut.textContent = settings.comfort.scale.toFixed(2);
    }
    for (const [zone, btn] of this.muteBtns) btn.setAttribute("aria-pressed", String(!!settings.comfort.mute[zone]));
  }

  destroy() {
    if (this._unwatch) this._unwatch();
    this._unwatch = null;
    this.clearListeners();
  }
}
