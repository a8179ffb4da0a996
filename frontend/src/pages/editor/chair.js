/**
 * The chair in the editor: the diagram of the values at the playhead (at the chair while a push
 * plays it apart from the player), the connection panel, the player's reports to a connected
 * chair, and STOP (the button and Escape).
 */

import { h } from "../../core/dom.js";
import { ChairDiagram } from "../../chair/diagram.js";
import { ChairPanel } from "../../chair/panel.js";
import { ChairSync } from "../../chair/sync.js";
import { formatTime } from "../../data/format.js";
import { errorText } from "../../data/http.js";
import { toast } from "../../panels/widgets.js";

export class EditorChair {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {ChairDiagram|null} */
    this.diagram = null;
    /** @type {ChairPanel|null} */
    this.panel = null;
    /** @type {ChairSync|null} */
    this.sync = null;
    /** what the diagram shows: "chair"|"playhead" and the tick ("" = show again) */
    this.shown = "";
  }

  /** The "At the playhead" panel with the chair diagram. */
  buildDiagram() {
    const host = h("div", { class: "chair", "data-testid": "chair-diagram" });
    this.diagram = new ChairDiagram(host, { actuators: this.page.layout.actuators, temperature: this.page.tempRange() });
    this.diagramTitle = h("h2", { class: "panel-title", id: "chair-title", "data-testid": "chair-diagram-title" }, "At the playhead");
    return h("section", { class: "panel", "aria-labelledby": "chair-title" }, this.diagramTitle, host);
  }

  /**
   * Show the values where the chair is on the diagram: during a push of this project the push's
   * position, else the player's. Redraws only when the tick or the source changes.
   * @param {number} playerS the player's position (s)
   * @param {boolean} [force] draw even if the same tick is shown (new data)
   */
  showDiagram(playerS, force = false) {
    const data = this.page.data;
    const pushS = this.panel ? this.panel.pushPositionS : null;
    const source = pushS === null ? "playhead" : "chair";
    const tick = data ? data.tickAt(pushS === null ? playerS : pushS) : -1;
    const key = `${source}:${tick}`;
    if (!force && data && key === this.shown) return;
    this.shown = key;
    this.diagram.update(data ? data.valuesAt(tick) : null);
    const host = /** @type {HTMLElement} */ (this.diagram.root.parentElement);
    host.dataset.source = source;
    host.dataset.tick = String(tick);
    this.diagramTitle.textContent = pushS === null ? "At the playhead" : `At the chair · ${formatTime(pushS)}`;
  }

  /** The connection panel; while a chair is connected the player reports to it. Needs the player. */
  buildPanel() {
    const page = this.page;
    this.panel = new ChairPanel(page.api, { projectId: page.projectId, tickS: page.tickS, range: () => this._pushRange() });
    this.sync = new ChairSync(page.api, page.projectId, page.media.player, { onError: (m) => toast(`The chair did not follow: ${m}`, "warn") });
    page.cleanups.push(
      this.panel.on("status", ({ status, active }) => {
        this.sync.setActive(active);
        page.header.showChair(status.state);
        page.timeline?.setChairHead(this.panel.pushPositionS);  // a push plays the chair apart from the player
        this.showDiagram(page.media.player.currentTime);
      }),
      () => this.sync.destroy(),
      () => this.panel.destroy(),
    );
    return this.panel.el;
  }

  /** STOP wins over everything else Escape does, wherever the focus is (a text field, a dialog). */
  stopOnEscape() {
    const onEscape = (/** @type {KeyboardEvent} */ e) => {
      if (e.key === "Escape" && this.panel && this.panel.active) this.stop();
    };
    document.addEventListener("keydown", onEscape, true);
    this.page.cleanups.push(() => document.removeEventListener("keydown", onEscape, true));
  }

  /** What "Push" sends to the chair: the selection, else the whole film (seconds). */
  _pushRange() {
    const tl = this.page.timeline;
    const sel = tl && tl.selection;
    if (sel) return { startS: sel.t0 * this.page.tickS, endS: sel.t1 * this.page.tickS, label: "selection" };
    return { startS: 0, endS: tl ? tl.durationS : 0, label: "whole film" };
  }

  /** STOP the chair: every output off now, the player paused, queued playback reports dropped. */
  async stop() {
    const page = this.page;
    const racing = this.sync ? this.sync.halt() : null;
    const stop = () => (this.panel ? this.panel.stop() : page.api.chairStop().catch((err) => toast(`STOP failed: ${errorText(err)}`, "error")));
    const stopping = stop();
    const player = page.media.player;
    if (player && player.playing) player.pause();
    await stopping;
    if (racing) {
      // A play report already on its way may reach the server after the STOP and restart the
      // chair: once it has landed, STOP again.
      await racing;
      await stop();
    }
  }
}
