/**
 * The chair diagram: the actuators at the playhead (colour and size = intensity) on a seat
 * outline, with the temperature and the share of fans that are on. Positions come from the
 * layout the server sends (/api/config), grouped by zone: back, armrests, seat.
 */

import { heatColor, temperatureColor } from "../core/colormap.js";

const SVG = "http://www.w3.org/2000/svg";

/** @typedef {import("../data/layout.js").ActuatorInfo} ActuatorInfo */

/**
 * @param {string} tag
 * @param {Record<string, string|number>} attrs
 */
function svg(tag, attrs) {
  const el = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, String(v));
  return el;
}

/** @param {ActuatorInfo} a @returns {[number, number]} */
function place(a) {
  if (a.zone === "armrests") return [a.x < 0.5 ? 22 : 178, 128];
  if (a.zone === "seat") return [46 + a.x * 108, 182];
  return [46 + a.x * 108, 34 + a.y * 140];
}

export class ChairDiagram {
  /**
   * @param {HTMLElement} host
   * @param {{actuators: ActuatorInfo[], temperature: import("../data/layout.js").TemperatureRange}} opts
   *   the actuators in the order of a tick's `vibration` values
   */
  constructor(host, { actuators, temperature }) {
    this.temperature = temperature;
    this.ids = actuators.map((a) => a.id);
    const root = svg("svg", { viewBox: "0 0 200 250", class: "chair-svg", role: "img", "aria-label": "Chair: actuator intensities at the playhead" });
    root.setAttribute("data-testid", "chair");
    root.append(
      svg("rect", { x: 38, y: 8, width: 124, height: 124, rx: 16, class: "chair-part" }),
      svg("rect", { x: 8, y: 92, width: 28, height: 74, rx: 10, class: "chair-part" }),
      svg("rect", { x: 164, y: 92, width: 28, height: 74, rx: 10, class: "chair-part" }),
      svg("rect", { x: 38, y: 140, width: 124, height: 70, rx: 14, class: "chair-part" }),
    );
    /** @type {Map<string, {dot: SVGCircleElement, label: SVGElement, title: SVGTitleElement, body: string}>} */
    this.dots = new Map();
    for (const a of actuators) {
      const [cx, cy] = place(a);
      const g = svg("g", { class: "chair-act" });
      g.setAttribute("data-testid", `chair-${a.id}`);
      const dot = /** @type {SVGCircleElement} */ (svg("circle", { cx, cy, r: 9, fill: heatColor(0) }));
      const label = svg("text", { x: cx, y: cy + 3.5, "text-anchor": "middle", class: "chair-label" });
      label.textContent = a.id;
      const title = /** @type {SVGTitleElement} */ (svg("title", {}));
      g.append(title, dot, label);
      root.append(g);
      this.dots.set(a.id, { dot, label, title, body: a.body || a.zone });
    }
    this.tempRect = svg("rect", { x: 38, y: 220, width: 124, height: 24, rx: 6, class: "chair-temp" });
    this.tempText = svg("text", { x: 100, y: 236, "text-anchor": "middle", class: "chair-temp-text" });
    this.tempText.setAttribute("data-testid", "chair-temperature");
    root.append(this.tempRect, this.tempText);
    this.fansText = document.createElement("div");
    this.fansText.className = "chair-fans";
    this.fansText.setAttribute("data-testid", "chair-fans");
    host.append(root, this.fansText);
    this.root = root;
  }

  /**
   * @param {import("../data/timeline-data.js").TickValues|null} v values at the playhead (null: no timeline)
   */
  update(v) {
    this.ids.forEach((id, i) => {
      const d = this.dots.get(id);
      if (!d) return;
      const value = v ? v.vibration[i] : 0;
      d.dot.setAttribute("fill", heatColor(value));
      d.dot.setAttribute("r", String(8 + 7 * value));
      d.label.classList.toggle("chair-label-dark", value > 0.55);
      d.dot.parentElement?.setAttribute("data-value", value.toFixed(3));
      d.title.textContent = `${id} (${d.body}): ${value.toFixed(2)}`;
    });
    const { lo, hi, neutral } = this.temperature;
    const c = v ? v.temperature_c : neutral;
    this.tempRect.setAttribute("fill", temperatureColor(c, neutral, lo, hi));
    this.tempText.textContent = v ? `${c.toFixed(1)} °C` : "–";
    this.fansText.textContent = v ? `Fans on: ${Math.round(v.fans * 100)} %` : "";
  }
}
