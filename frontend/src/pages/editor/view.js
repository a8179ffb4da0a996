/**
 * View settings: zoom, scroll, hidden lanes, the fan overlay, follow, the detail lane's
 * actuator and whether the Shots panel is open. Saved with the project (PATCH, debounced), never undoable; restored when it opens.
 */

import { errorText } from "../../data/http.js";
import { toast } from "../../panels/widgets.js";

const VIEW_SAVE_DELAY_MS = 600;

export class ViewSettings {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    /** @type {ReturnType<typeof setTimeout>|null} */
    this._timer = null;
    this._restoring = false;
  }

  /** Apply saved settings; restoring them saves nothing. @param {Record<string, any>} view */
  restore(view) {
    const page = this.page;
    this._restoring = true;
    if (Array.isArray(view.hidden_lanes)) for (const id of view.hidden_lanes) page.lanes.hide(id);
    if (typeof view.detail_actuator === "string") page.lanes.detail.setActuator(view.detail_actuator);
    if (view.fan_overlay) page.media.setOverlay(true);
    if (view.follow === false) page.media.setFollow(false);
    if (view.shots_panel) page.shots.panel.show(true);
    if (typeof view.px_per_s === "number") {
      // The width is known after the first layout; restore then.
      requestAnimationFrame(() => {
        page.timeline.restoreView({ pxPerS: view.px_per_s, startS: view.start_s });
        this._restoring = false;
      });
    } else {
      this._restoring = false;
    }
  }

  scheduleSave() {
    if (this._restoring || !this.page.timeline) return;
    if (this._timer) clearTimeout(this._timer);
    this._timer = setTimeout(() => this._save(), VIEW_SAVE_DELAY_MS);
  }

  /** Save now what is still waiting to be saved (the editor is closing). */
  flush() {
    if (!this._timer) return;
    clearTimeout(this._timer);
    this._save();
  }

  async _save() {
    this._timer = null;
    const page = this.page;
    const tl = page.timeline;
    const view = {
      px_per_s: Math.round(tl.pxPerS * 1000) / 1000,
      start_s: Math.round(tl.startS * 1000) / 1000,
      hidden_lanes: tl.lanes.filter((l) => l.row.hidden).map((l) => l.lane.id),
      fan_overlay: page.media.fanOverlay.visible,
      follow: tl.follow,
      detail_actuator: page.lanes.detail.actuator,
      shots_panel: page.shots.panel.open,
    };
    try {
      await page.api.patchProject(page.projectId, { view });
    } catch (err) {
      if (!page.disposed) toast(`The view settings were not saved: ${errorText(err)}`, "warn");
    }
  }
}
