/**
 * Read-only views of an open editor for tests and the benchmark (window.autohaptics, main.js).
 * They copy what they return, so nothing outside can change the editor through them.
 */

/** @typedef {import("./shell.js").EditorPage} EditorPage */

/** A snapshot of the editor's state. @param {EditorPage} page */
export function debugState(page) {
  const { timeline: tl, session, data, media, chair } = page;
  const player = media.player;
  const saveEl = page.header.saveEl;
  return {
    projectId: page.projectId,
    revision: session ? session.revision : null,
    cursor: session ? session.cursor : null,
    nOps: session ? session.nOps : null,
    ready: !!data,
    dataRevision: data ? data.revision : null,
    pyramidsBuilt: data ? data.pyramidsBuilt : null,
    drawnRevision: page.drawnRevision ?? null,
    nTicks: data ? data.nTicks : null,
    playing: player ? player.playing : false,
    currentTime: player ? player.currentTime : 0,
    playheadS: tl ? tl.playheadS : 0,
    pxPerS: tl ? tl.pxPerS : null,
    startS: tl ? tl.startS : null,
    visibleS: tl ? tl.visibleS : null,
    durationS: tl ? tl.durationS : null,
    selection: tl && tl.selection ? { ...tl.selection, lanes: [...tl.selection.lanes] } : null,
    tool: tl ? tl.tool : null,
    thresholds: { ...page.params.thresholds },
    played: page.played
      ? { revision: page.played.revision, minC: page.played.minC, maxC: page.played.maxC, lo: page.played.lo, hi: page.played.hi }
      : null,
    markers: page.markers.list.map((m) => ({ ...m })),
    shots: page.shots.debug(),
    timing: { ...page.timing },
    waveformReady: !Number.isNaN(page.timing.waveformLoaded),
    saveState: saveEl ? saveEl.dataset.state || "" : "",
    jobActive: page.jobs.followed > 0,
    chair: chair.panel && chair.panel.status
      ? { active: chair.panel.active, state: chair.panel.status.state, reporting: chair.sync.active,
          reportsPending: chair.sync.pending }
      : null,
  };
}

/** Values of the composed timeline at one tick (a copy). @param {EditorPage} page @param {number} tick */
export function valuesAt(page, tick) {
  if (!page.data) return null;
  const v = page.data.valuesAt(tick);
  const played = page.played && page.played.revision === page.data.revision ? page.played.at(tick) : null;
  return { vibration: v.vibration, temperature_c: v.temperature_c, played_c: played, fans: v.fans, fan_grid: Array.from(v.fan_grid), features: v.features };
}

/** Page rectangle (client px) of a lane's canvas, for tests that point at lanes. @param {EditorPage} page @param {string} id */
export function laneRect(page, id) {
  const e = page.timeline && page.timeline.laneEntry(id);
  if (!e) return null;
  const r = e.canvas.getBoundingClientRect();
  return { x: r.x, y: r.y, width: r.width, height: r.height };
}

/** Client x of a time on the timeline. @param {EditorPage} page @param {number} timeS */
export function clientXOf(page, timeS) {
  const r = page.timeline.rulerCanvas.getBoundingClientRect();
  return r.x + page.timeline.timeToX(timeS);
}
