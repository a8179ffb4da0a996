/**
 * The time ruler above the lanes: 1-2-5 ticks with labels at the current zoom, and the selected
 * range as a band along its bottom edge.
 */

export const RULER_HEIGHT = 24;

/**
 * @param {CanvasRenderingContext2D} ctx the ruler canvas, `dpr` device pixels per CSS pixel
 * @param {number} dpr
 * @param {import("./timeline.js").TimelineView} view
 */
export function drawRuler(ctx, dpr, view) {
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.clearRect(0, 0, view.width, RULER_HEIGHT);
  const step = niceStep(80 / view.pxPerS);
  const minor = step / 5;
  ctx.fillStyle = "#8b93a7";
  ctx.strokeStyle = "#3a4152";
  ctx.font = "11px system-ui, sans-serif";
  ctx.textBaseline = "top";
  ctx.beginPath();
  const first = Math.floor(view.startS / minor) * minor;
  for (let t = first; t <= view.endS + minor; t += minor) {
    const x = Math.round(view.timeToX(t)) + 0.5;
    const major = Math.abs(t / step - Math.round(t / step)) < 1e-6;
    ctx.moveTo(x, major ? 12 : 18);
    ctx.lineTo(x, RULER_HEIGHT);
    if (major && t >= 0) ctx.fillText(formatRulerTime(t, step), x + 3, 2);
  }
  ctx.stroke();
  const sel = view.selection;
  if (sel) {
    ctx.fillStyle = "rgba(96, 165, 250, 0.35)";
    ctx.fillRect(view.tickToX(sel.t0), RULER_HEIGHT - 5, view.tickToX(sel.t1) - view.tickToX(sel.t0), 5);
  }
}

/** A 1-2-5 step (seconds) at least `minS`. @param {number} minS */
export function niceStep(minS) {
  const steps = [0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600];
  for (const s of steps) if (s >= minS) return s;
  return 3600 * Math.ceil(minS / 3600);
}

/** @param {number} t @param {number} step */
function formatRulerTime(t, step) {
  const h = Math.floor(t / 3600);
  const m = Math.floor((t % 3600) / 60);
  const s = t % 60;
  const sec = step < 1 ? s.toFixed(1).padStart(4, "0") : String(Math.round(s)).padStart(2, "0");
  return h ? `${h}:${String(m).padStart(2, "0")}:${sec}` : `${m}:${sec}`;
}
