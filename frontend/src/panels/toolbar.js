/**
 * The editing toolbar: tools, the lanes an edit applies to, and one button per operation. It
 * holds no state of its own; the editor calls `update()` with what is selected. The markers'
 * buttons, the temperature points' Apply / Discard and the selection's description (`markersEl`,
 * `pointsGroup`, `info`) go at the end of the transport bar, so the toolbar keeps to one line at 1366 px.
 */

import { h } from "../core/dom.js";
import { formatTime } from "../data/format.js";
const LANE_TEXT = /** @type {Record<string, string>} */ ({ temperature: "Temp", fans: "Fans" });

/**
 * @typedef {{
 *   tool: (tool: "select"|"pencil"|"points") => void,
 *   toggleLane: (lane: string) => void,
 *   set: (value: number) => void,
 *   scale: (factor: number) => void,
 *   clear: () => void,
 *   fade: (kind: "in"|"out") => void,
 *   copy: () => void,
 *   paste: () => void,
 *   applyPoints: () => void,
 *   discardPoints: () => void,
 *   addMarker: () => void,
 *   renameMarker: () => void,
 *   deleteMarker: () => void,
 *   splitShot: () => void,
 *   mergeShot: () => void,
 * }} ToolbarActions
 */

export class EditToolbar {
  /**
   * @param {ToolbarActions} actions
   * @param {string[]} editLanes the lanes an edit can address (/api/config `lanes`)
   */
  constructor(actions, editLanes) {
    const btn = (/** @type {string} */ text, /** @type {string} */ testid, /** @type {() => void} */ fn, /** @type {string} */ title = "") =>
      h("button", { class: "btn btn-small", type: "button", "data-testid": testid, title: title || undefined, onclick: fn }, text);

    /** @type {Record<string, HTMLButtonElement>} */
    this.tools = {
      select: btn("Select", "tool-select", () => actions.tool("select"), "Select ranges (drag on lanes)"),
      pencil: btn("Pencil", "tool-pencil", () => actions.tool("pencil"), "Draw values on the Detail or Temperature lane"),
      points: btn("Points", "tool-points", () => actions.tool("points"), "Temperature points: place breakpoints on the Temperature lane"),
    };
    const toolGroup = h("div", { class: "btn-group", role: "group", "aria-label": "Tool" }, ...Object.values(this.tools));

    /** @type {Map<string, HTMLButtonElement>} */
    this.chips = new Map();
    const chipGroup = h("div", { class: "chip-group", role: "group", "aria-label": "Lanes the edit applies to" });
    for (const lane of editLanes) {
      const chip = h("button", { class: "chip", type: "button", "aria-pressed": "false", "data-testid": `lane-chip-${lane}`, onclick: () => actions.toggleLane(lane) }, LANE_TEXT[lane] || lane);
      this.chips.set(lane, chip);
      chipGroup.append(chip);
    }

    this.value = h("input", { type: "number", class: "input input-num", step: 0.05, value: "0.5", "aria-label": "Value to set (0..1, or °C for temperature)", "data-testid": "edit-value" });
    this.factor = h("input", { type: "number", class: "input input-num", step: 0.1, min: 0, value: "1.5", "aria-label": "Scale factor", "data-testid": "edit-factor" });
    this.setBtn = btn("Set", "edit-set", () => actions.set(this.value.valueAsNumber), "Set the selection to the value");
    this.scaleBtn = btn("Scale", "edit-scale", () => actions.scale(this.factor.valueAsNumber), "Multiply the selection by the factor");
    this.clearBtn = btn("Clear", "edit-clear", () => actions.clear(), "Clear the selection (Delete)");
    this.fadeInBtn = btn("Fade in", "edit-fade-in", () => actions.fade("in"));
    this.fadeOutBtn = btn("Fade out", "edit-fade-out", () => actions.fade("out"));
    this.copyBtn = btn("Copy", "edit-copy", () => actions.copy(), "Copy the selection (Ctrl+C)");
    this.pasteBtn = btn("Paste", "edit-paste", () => actions.paste(), "Paste at the playhead (Ctrl+V)");
    this.applyPointsBtn = btn("Apply points", "points-apply", () => actions.applyPoints());
    this.discardPointsBtn = btn("Discard", "points-discard", () => actions.discardPoints());
    this.pointsGroup = h("div", { class: "btn-group", role: "group", "aria-label": "Temperature points" }, this.applyPointsBtn, this.discardPointsBtn);
    this.markerAdd = btn("Add marker", "marker-add", () => actions.addMarker(), "Add a marker at the playhead");
    this.markerRename = btn("Rename", "marker-rename", () => actions.renameMarker());
    this.markerDelete = btn("Delete", "marker-delete", () => actions.deleteMarker());
    this.splitBtn = btn("Split", "shot-split", () => actions.splitShot(), "Split the shot at the playhead (S)");
    this.mergeBtn = btn("Merge", "shot-merge", () => actions.mergeShot(), "Merge the shot at the playhead with the next (M)");
    this.info = h("span", { class: "selection-info", "data-testid": "selection-info", "aria-live": "polite" });
    this.markersEl = h("div", { class: "btn-group", role: "group", "aria-label": "Markers" }, this.markerAdd, this.markerRename, this.markerDelete);
    this.editLanes = editLanes;

    this.el = h(
      "div",
      { class: "toolbar", role: "toolbar", "aria-label": "Editing" },
      toolGroup,
      chipGroup,
      h("div", { class: "btn-group" }, this.value, this.setBtn),
      h("div", { class: "btn-group" }, this.factor, this.scaleBtn),
      h("div", { class: "btn-group" }, this.clearBtn, this.fadeInBtn, this.fadeOutBtn),
      h("div", { class: "btn-group" }, this.copyBtn, this.pasteBtn),
      h("div", { class: "btn-group", role: "group", "aria-label": "Shots" }, this.splitBtn, this.mergeBtn),
    );
  }

  /**
   * @param {{tool: string, selection: import("../core/timeline.js").Selection|null, lanes: string[],
   *   tickS: number, canPaste: boolean, points: number, markerSelected: boolean, ready: boolean, cells?: number,
   *   shots?: boolean}} s
   */
  update(s) {
    for (const [name, b] of Object.entries(this.tools)) b.setAttribute("aria-pressed", String(name === s.tool));
    for (const [lane, chip] of this.chips) chip.setAttribute("aria-pressed", String(s.lanes.includes(lane)));
    const has = !!s.selection && s.ready;
    for (const b of [this.scaleBtn, this.clearBtn, this.fadeInBtn, this.fadeOutBtn, this.copyBtn]) b.disabled = !has;
    const mixed = s.lanes.includes("temperature") && s.lanes.length > 1;
    this.setBtn.disabled = !has || mixed;
    this.setBtn.title = mixed ? "Select temperature on its own to set a temperature" : "Set the selection to the value";
    this.value.setAttribute("aria-label", s.lanes.length === 1 && s.lanes[0] === "temperature" ? "Temperature to set, °C" : "Value to set, 0..1");
    this.pasteBtn.disabled = !s.canPaste || !s.ready;
    const ranges = s.selection && s.selection.ranges ? s.selection.ranges : null;
    this.copyBtn.title = ranges && ranges.length > 1 ? "Copy takes one shot: select one (Ctrl+C)" : "Copy the selection (Ctrl+C)";
    this.pasteBtn.title = ranges ? `Paste onto the ${ranges.length} selected shot(s), fitted to each (Ctrl+V)` : "Paste at the playhead (Ctrl+V)";
    this.splitBtn.disabled = this.mergeBtn.disabled = !s.shots || !s.ready;
    this.pointsGroup.hidden = s.tool !== "points";
    this.applyPointsBtn.disabled = s.points === 0;
    this.discardPointsBtn.disabled = s.points === 0;
    this.markerAdd.disabled = !s.ready;
    this.markerRename.disabled = !s.markerSelected;
    this.markerDelete.disabled = !s.markerSelected;
    const lanes = lanesText(s.lanes, this.editLanes);
    if (ranges) {
      const ticks = ranges.reduce((n, [a, b]) => n + b - a, 0);
      this.info.textContent = `${ranges.length} shot${ranges.length === 1 ? "" : "s"} from ${formatTime(s.selection.t0 * s.tickS)} (${ticks} ticks) on ${lanes}`;
    } else if (s.selection) {
      const { t0, t1 } = s.selection;
      const region = s.cells && s.lanes.includes("fans") ? ` (${s.cells} fans picked on the grid)` : "";
      this.info.textContent = `${formatTime(t0 * s.tickS)} – ${formatTime(t1 * s.tickS)} (${t1 - t0} ticks) on ${lanes}${region}`;
    } else {
      this.info.textContent = s.tool === "points" ? "Click the Temperature lane to place points" : "Drag on the lanes to select a range";
    }
    this.info.title = this.info.textContent;
  }
}

/**
 * The lanes as the toolbar names them, runs of three or more neighbouring chips as "first–last"
 * ("A1–A9, Temp"). @param {string[]} lanes @param {string[]} order the chips' order
 */
export function lanesText(lanes, order) {
  const on = new Set(lanes);
  const parts = [];
  for (let i = 0; i < order.length; i++) {
    if (!on.has(order[i])) continue;
    let j = i;
    while (j + 1 < order.length && on.has(order[j + 1])) j++;
    const name = (/** @type {number} */ k) => LANE_TEXT[order[k]] || order[k];
    if (j - i >= 2) parts.push(`${name(i)}–${name(j)}`);
    else for (let k = i; k <= j; k++) parts.push(name(k));
    i = j;
  }
  return parts.join(", ") + lanes.filter((l) => !order.includes(l)).map((l) => `, ${l}`).join("");
}
