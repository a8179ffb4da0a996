/**
 * Entry point: loads /api/config once, then routes by the URL hash:
 *   #/                   the projects screen
 *   #/project/<id>       the editor
 * and exposes the read-only debug handle `window.autohaptics` (tests and the benchmark read it).
 */

import { h } from "./core/dom.js";
import { Api } from "./data/api.js";
import { errorText } from "./data/http.js";
import { chairLayout } from "./data/layout.js";
import { clientXOf, debugState, laneRect, valuesAt } from "./pages/editor/debug.js";
import { startEditorLoads } from "./pages/editor/loading.js";
import { EditorPage } from "./pages/editor/shell.js";
import { ProjectsPage } from "./pages/projects.js";

const api = new Api("");
const app = /** @type {HTMLElement} */ (document.getElementById("app"));
/** @type {EditorPage|ProjectsPage|null} */
let page = null;
/** @type {Record<string, any>} */
let config = {};
/** @type {import("./data/layout.js").ChairLayout|null} the chair, as config describes it */
let layout = null;

/** The project id of an editor URL (#/project/<id>), else null. */
function editorRoute() {
  const m = location.hash.match(/^#\/project\/([^/?#]+)/);
  return m ? decodeURIComponent(m[1]) : null;
}

/** @param {import("./pages/editor/loading.js").EditorLoads} [loads] requests already started for this route */
async function route(loads) {
  if (page) page.destroy();
  page = null;
  delete app.dataset.ready;
  const id = editorRoute();
  if (id) {
    const editor = new EditorPage(app, { api, config, layout }, id);
    page = editor;
    await editor.open(loads);
  } else {
    const list = new ProjectsPage(app, { api, config });
    page = list;
    await list.open();
  }
}

function installDebugHandle() {
  const editor = () => (page instanceof EditorPage ? page : null);
  const handle = {
    /** Which screen is shown. */
    get screen() {
      return page instanceof EditorPage ? "editor" : page instanceof ProjectsPage ? "projects" : "none";
    },
    /** A snapshot of the editor's state (null on the projects screen). */
    state() {
      const e = editor();
      return e ? debugState(e) : null;
    },
    /** Composed values at one tick: {vibration[9], temperature_c, fans, fan_grid[153], features}. */
    valuesAt(/** @type {number} */ tick) {
      const e = editor();
      return e ? valuesAt(e, tick) : null;
    },
    /** Page rectangle of a lane canvas ("waveform", "feature-loudness", "actuators", "detail", "temperature", "fans", "markers"). */
    laneRect(/** @type {string} */ id) {
      const e = editor();
      return e ? laneRect(e, id) : null;
    },
    /** Client x of a time (seconds) on the timeline. */
    clientXOf(/** @type {number} */ timeS) {
      const e = editor();
      return e ? clientXOf(e, timeS) : null;
    },
    /** Frame statistics of the editor's animation-frame loop (ms). */
    perf() {
      const e = editor();
      return e ? e.loop.stats() : null;
    },
    /** Start a fresh frame-time measurement. */
    resetPerf() {
      const e = editor();
      if (e) e.loop.resetStats();
    },
    /** Number of lane redraw passes so far. */
    renderCount() {
      const e = editor();
      return e && e.timeline ? e.timeline.renderCount || 0 : 0;
    },
  };
  Object.defineProperty(window, "autohaptics", { value: Object.freeze(handle), writable: false, configurable: false });
}

/** @param {string} text why the app cannot start */
function fatal(text) {
  app.replaceChildren(h("div", { class: "empty", role: "alert", "data-testid": "fatal" }, text));
}

async function start() {
  installDebugHandle();
  // `autohaptics serve --open-sample` opens /?project=<id>: turn it into the editor's route.
  const asked = new URLSearchParams(location.search).get("project");
  if (asked) history.replaceState(null, "", `${location.pathname}#/project/${encodeURIComponent(asked)}`);
  const id = editorRoute();
  // index.html started the first requests while the modules loaded (window.autohapticsEarly).
  const early = /** @type {any} */ (window).autohapticsEarly || null;
  const loads = id ? startEditorLoads(api, id, early && early.id === id ? early : null) : undefined;
  try {
    config = await (early ? api.readJson(early.config, "GET /api/config") : api.config());
  } catch (err) {
    fatal(`The autohaptics server is not answering: ${errorText(err)}`);
    return;
  }
  try {
    layout = chairLayout(config);
  } catch (err) {
    fatal(`The autohaptics server sent an incomplete configuration: ${errorText(err)}`);
    return;
  }
  window.addEventListener("hashchange", () => {
    route();
  });
  await route(loads);
}

start();
