/**
 * The editor's lanes, top to bottom: shots (the filmstrip, ./shots.js), audio, one per feature, the actuators' heat map, one
 * actuator's detail, temperature, fans, markers; and the "Lanes" menu that shows or hides them.
 * Each lane reads the current timeline through the page and reports edits back to its parts.
 * Lane heights the user drags are kept in this browser for every project (data/local-store.js).
 */

import { h } from "../../core/dom.js";
import { readLocal, writeLocal } from "../../data/local-store.js";
import { ActuatorsLane } from "../../lanes/actuators.js";
import { FansLane } from "../../lanes/fans.js";
import { FeatureLane } from "../../lanes/features.js";
import { MarkersLane } from "../../lanes/markers.js";
import { TemperatureLane } from "../../lanes/temperature.js";
import { VibrationDetailLane } from "../../lanes/vibration-detail.js";
import { WaveformLane } from "../../lanes/waveform.js";

const HEIGHTS_KEY = "laneHeights";

export class EditorLanes {
  /** @param {import("./shell.js").EditorPage} page */
  constructor(page) {
    this.page = page;
    this.menu = h("details", { class: "menu", "data-testid": "lanes-menu" }, h("summary", { class: "btn" }, "Lanes"));
    /** @type {FeatureLane[]} */
    this.features = [];
  }

  /**
   * Create the lanes on the timeline and list them in the menu.
   * @param {import("../../core/timeline.js").TimelineView} tl
   * @param {string[]} features
   */
  add(tl, features) {
    const page = this.page;
    const data = () => page.data;
    const params = page.params;
    this.waveform = new WaveformLane();
    this.features = features.map((name) =>
      new FeatureLane(name, {
        data,
        threshold: (n) => (n in params.thresholds ? params.thresholds[n] : null),
        onInput: (n, v) => params.input(n, v),
        onCommit: (n, v) => params.commit(n, v),
        onCancel: (n) => params.cancel(n),
      }));
    this.actuators = new ActuatorsLane({ data, actuators: page.layout.actuators });
    this.detail = new VibrationDetailLane({
      data,
      actuatorIds: page.layout.actuatorIds,
      onPencil: (op) => page.edits.submitStroke(op, this.detail),
      onChange: () => {
        tl.invalidate("detail");
        page.view.scheduleSave();
      },
    });
    this.temperature = new TemperatureLane({
      data,
      range: () => page.tempRange(),
      played: () => page.played,
      onPencil: (op) => page.edits.submitStroke(op, this.temperature),
      onPointsChange: (pts) => page.edits.takePoints(pts),
    });
    this.fans = new FansLane({ data, grid: { rows: page.layout.fanRows, cols: page.layout.fanCols } });
    const markers = page.markers;
    this.markers = new MarkersLane({
      markers: () => markers.list,
      selected: () => markers.selected,
      onSelect: (id) => markers.select(id),
      onMove: (id, t) => markers.move(id, t),
      onAdd: (t) => markers.add(t),
      onRename: (id) => markers.rename(id),
    });
    const shots = page.shots.lane(tl);
    for (const lane of [shots, this.waveform, ...this.features, this.actuators, this.detail, this.temperature, this.fans, this.markers]) tl.addLane(lane);
    page.shots.wireContextMenu(/** @type {import("../../core/timeline.js").LaneEntry} */ (tl.laneEntry("shots")).canvas);
    this._fillMenu(tl);
    this._keepHeights(tl);
  }

  /** Give the lanes the heights the user set before and keep each new one. @param {import("../../core/timeline.js").TimelineView} tl */
  _keepHeights(tl) {
    const saved = /** @type {Record<string, number>} */ (readLocal(HEIGHTS_KEY, {}));
    for (const { lane } of tl.lanes) {
      const px = saved && saved[lane.id];
      if (typeof px === "number" && Number.isFinite(px)) tl.setLaneHeight(lane.id, px);
    }
    this.page.cleanups.push(tl.on("lane-height", ({ id, height }) => {
      writeLocal(HEIGHTS_KEY, { ...readLocal(HEIGHTS_KEY, {}), [id]: height });
    }));
  }

  /** @param {import("../../core/timeline.js").TimelineView} tl */
  _fillMenu(tl) {
    const list = h("div", { class: "menu-list menu-checks" });
    for (const { lane } of tl.lanes) {
      const cb = h("input", { type: "checkbox", checked: true, "data-testid": `lane-toggle-${lane.id}` });
      cb.addEventListener("change", () => {
        tl.setLaneVisible(lane.id, cb.checked);
        this.page.view.scheduleSave();
      });
      list.append(h("label", { class: "menu-check" }, cb, lane.label));
    }
    this.menu.append(list);
  }

  /** Hide a lane as saved view settings say, its menu entry unchecked. @param {string} id */
  hide(id) {
    this.page.timeline.setLaneVisible(id, false);
    const cb = /** @type {HTMLInputElement|null} */ (this.menu.querySelector(`[data-testid="lane-toggle-${id}"]`));
    if (cb) cb.checked = false;
  }
}
