"""Editor performance on a 2-hour film (72,000 ticks): a script that prints figures, not a test.

    .venv/bin/python tests/browser/bench_editor.py            # about 3 minutes the first time
    .venv/bin/python tests/browser/bench_editor.py --runs 10  # more opening runs

What it does, through the real service and Debian's Chromium:

1. Writes a 2-hour low-resolution film with sound (autohaptics.testing, cached in out/bench/), uploads
   it to a private ``autohaptics serve`` and lets the real pipeline generate its timeline (the
   project is kept in out/bench/ and reused by later runs). A few edits give every lane content:
   temperature points across the film, fans in scenes, markers.
2. Opening, ``--runs`` times in fresh browser contexts, read from the editor's own marks: the
   time to the first complete draw of every lane (a) when the project is opened from the projects
   list (project, edits, timeline.bin, parsing, pyramids, drawing) and (b) when its URL is loaded
   cold, from navigation start (the page and its modules too); plus the size and request time of
   timeline.bin.
3. Playback: plays the film for ``--seconds`` in three views and reads the frame loop's statistics:
   ``work`` = milliseconds spent in the editor's animation-frame callbacks per frame (the playhead,
   the chair diagram, the fan overlay and every lane redraw), ``interval`` = time between frames.
   Views: the whole film in view (playhead only), zoomed to 400 px/s with follow (the view pages
   every ~3 s of film), and the whole film while the user pans with the wheel every frame (every
   lane redrawn every frame: the worst case).
4. Editing latency: threshold commits, lowering and raising (PUT /params -> re-derive -> reload ->
   redraw), and one edit (POST /edits -> reload -> redraw), from the user's release to the new
   revision on screen; then the editor's JS heap and the server's RSS with the project open.

Targets: first render < 1 s (cold URL too), frame time p95 < 16 ms, threshold release -> redrawn <= 200 ms. Results also go to test-artifacts/bench_editor.json.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parent))
from browser_support import (  # noqa: E402
    CHROMIUM, CHROMIUM_ARGS, REPO, api_client, open_editor, start_server, state, stop_server, wait_job,
    wait_revision_above,
)

DURATION_S = 7200.0
BENCH_DIR = REPO / "out" / "bench"
FILM = BENCH_DIR / "film-2h-64x36.mp4"
PROJECT_NAME = "bench 2 h"
RESULTS = REPO / "test-artifacts" / "bench_editor.json"
VIEWPORT = {"width": 1440, "height": 900}


def write_film(path: Path) -> None:
    """A 2-hour scene: 30 s colour segments, a boom, a blip or a whoosh every 7-10 s."""
    from autohaptics.testing import Noise, Scene, Segment, Tone, write_scene

    colours = [(40, 45, 60), (180, 50, 40), (40, 150, 60), (200, 180, 60), (60, 80, 170)]
    segments = tuple(Segment(t, min(DURATION_S, t + 30.0), colours[i % len(colours)])
                     for i, t in enumerate(float(s) for s in range(0, int(DURATION_S), 30)))
    audio = []
    t, k = 2.0, 0
    while t + 3.0 < DURATION_S:
        if k % 3 == 0:
            audio.append(Tone(t, t + 1.5, 50.0 + 20 * (k % 5), level_dbfs=-14.0 - (k % 7), ramp_s=0.05))
        elif k % 3 == 1:
            audio.append(Tone(t, t + 0.4, 2000.0, level_dbfs=-22.0 - (k % 5)))
        else:
            audio.append(Noise(t, t + 2.5, level_dbfs=-20.0 - (k % 6), colour="pink", seed=k, ramp_s=0.2))
        t += 7.0 + (k % 4)
        k += 1
    scene = Scene(duration_s=DURATION_S, background=segments, audio=tuple(audio), name="bench-2h")
    write_scene(path, scene, width=64, height=36, fps=5, long=True, quality="low", sample_rate=24000)


def ensure_project(api: httpx.Client) -> dict:
    """The generated 2-hour project (created once, then reused)."""
    for p in api.get("/api/projects").json():
        if p["name"] == PROJECT_NAME and p["status"] == "ready":
            return p
    if not FILM.exists():
        print(f"writing the 2-hour film {FILM} …", flush=True)
        t0 = time.perf_counter()
        BENCH_DIR.mkdir(parents=True, exist_ok=True)
        write_film(FILM)
        print(f"  {time.perf_counter() - t0:.0f} s, {FILM.stat().st_size / 2**20:.1f} MiB", flush=True)
    print("uploading and generating (the real pipeline) …", flush=True)
    t0 = time.perf_counter()
    with open(FILM, "rb") as fh:
        r = api.post("/api/projects", files={"file": (FILM.name, fh)}, data={"name": PROJECT_NAME})
    r.raise_for_status()
    project = r.json()
    job = wait_job(api, project["job"]["id"], timeout=1800)
    if job["status"] != "done":
        raise SystemExit(f"generation failed: {job}")
    print(f"  {time.perf_counter() - t0:.0f} s", flush=True)
    pid = project["id"]
    n = api.get(f"/api/projects/{pid}").json()["n_ticks"]
    ops = [
        {"op": "temp_points", "t0": 0, "t1": n,
         "points": [[k, 33.0 + 6.0 * ((k // 3000) % 3 - 1)] for k in range(0, n, 3000)] + [[n - 1, 33.0]]},
        *({"op": "set", "lanes": ["fans"], "t0": k, "t1": k + 150, "value": 0.6} for k in range(600, n, 6000)),
        *({"op": "marker_add", "marker": {"id": f"m{i}", "t_s": i * 600.0 + 30.0, "label": f"Reel {i + 1}"}}
          for i in range(12)),
    ]
    for op in ops:
        rev = api.get(f"/api/projects/{pid}/edits").json()["revision"]
        api.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": op}).raise_for_status()
    return api.get(f"/api/projects/{pid}").json()


def measure_open(browser, url: str, pid: str, runs: int) -> dict:
    """Fresh browser context per run (cold cache). Two ways in: the project's URL typed or
    reloaded (page, modules and data load together), and a click on the project in the projects
    list (the modules are loaded; what the designer does most)."""
    cold, from_list, steps, bin_ms, bin_bytes = [], [], [], [], 0
    for _ in range(runs):
        ctx = browser.new_context(viewport=VIEWPORT, base_url=url)
        pg = ctx.new_page()
        pg.goto(f"/#/project/{pid}")
        pg.wait_for_selector("#app[data-ready='true']", timeout=60_000)
        t = state(pg)["timing"]
        cold.append(t["start"] + t["firstRender"])
        res = pg.evaluate("""() => performance.getEntriesByType('resource')
            .filter((e) => e.name.includes('timeline.bin')).map((e) => [e.duration, e.encodedBodySize])""")
        if res:
            bin_ms.append(res[0][0])
            bin_bytes = res[0][1]
        pg.goto("/#/")
        pg.wait_for_selector(f"[data-id='{pid}'] [data-testid=project-open]")
        pg.click(f"[data-id='{pid}'] [data-testid=project-open]")
        pg.wait_for_selector("#app[data-ready='true']", timeout=60_000)
        t = state(pg)["timing"]
        from_list.append(t["firstRender"])
        steps.append(t)
        ctx.close()
    return {
        "runs": runs,
        "first_render_cold_url_ms": summary(cold),
        "first_render_from_list_ms": summary(from_list),
        "from_list_steps_ms": {k: summary([t[k] for t in steps])
                               for k in ("binFetched", "dataLoaded", "firstRender")},
        "timeline_bin_request_ms": summary(bin_ms),
        "timeline_bin_bytes": bin_bytes,
    }


def measure_playback(pg, seconds: float, scenario: str) -> dict:
    """Play ``seconds`` of film in one view and return the frame loop's statistics."""
    pg.evaluate("() => document.querySelector('[data-testid=video]').pause()")
    pg.wait_for_function("() => !window.autohaptics.state().playing")
    if scenario == "fit":
        pg.click("[data-testid=zoom-fit]")
    else:
        pg.click("[data-testid=zoom-fit]")
        if scenario == "zoomed-follow":
            for _ in range(30):
                pg.click("[data-testid=zoom-in]")
    pg.evaluate("() => { document.querySelector('[data-testid=video]').currentTime = 1800; }")
    pg.wait_for_function("() => Math.abs(window.autohaptics.state().currentTime - 1800) < 0.5")
    pg.evaluate("() => window.autohaptics.resetPerf()")
    renders0 = pg.evaluate("() => window.autohaptics.renderCount()")
    pg.click("[data-testid=play]")
    pg.wait_for_function("() => window.autohaptics.state().playing")
    t0 = time.perf_counter()
    if scenario == "fit-panning":
        pg.click("[data-testid=zoom-in]")  # leave room to pan
        pg.click("[data-testid=zoom-in]")
        wave = pg.evaluate("() => window.autohaptics.laneRect('actuators')")
        pg.mouse.move(wave["x"] + wave["width"] / 2, wave["y"] + 20)
        pg.evaluate("() => window.autohaptics.resetPerf()")
        direction = 1
        while time.perf_counter() - t0 < seconds:
            pg.mouse.wheel(0, 40 * direction)
            direction = -direction
    else:
        pg.wait_for_timeout(seconds * 1000)
    stats = pg.evaluate("() => window.autohaptics.perf()")
    renders = pg.evaluate("() => window.autohaptics.renderCount()") - renders0
    s = state(pg)
    pg.click("[data-testid=play]")
    return {"scenario": scenario, "px_per_s": round(s["pxPerS"], 4), "lane_redraws": renders,
            "played_s": round(s["currentTime"] - 1800, 2), **stats}


def drag_threshold(pg, feature: str, value: float) -> float:
    """Drag a threshold line to ``value`` and release it; wait for the new revision on screen and
    return the time from the release to it (ms)."""
    s0 = state(pg)
    rect = pg.evaluate(f"() => window.autohaptics.laneRect('feature-{feature}')")
    y = lambda v: rect["y"] + rect["height"] - 3 - v * (rect["height"] - 6)  # noqa: E731
    x = rect["x"] + rect["width"] * 0.5
    pg.mouse.move(x, y(s0["thresholds"][feature]))
    pg.mouse.down()
    pg.mouse.move(x, y(value), steps=4)
    t0 = pg.evaluate("() => performance.now()")
    pg.mouse.up()
    wait_revision_above(pg, s0["revision"])
    return pg.evaluate("() => performance.now()") - t0


def wait_no_job(api: httpx.Client, pid: str) -> None:
    """Until the project's refinement (if a commit started one) is over and its revision drawn."""
    deadline = time.monotonic() + 600
    while (job := api.get(f"/api/projects/{pid}").json()["job"]) and job["status"] in ("queued", "running"):
        if time.monotonic() > deadline:
            raise SystemExit(f"the refinement did not end: {job}")
        time.sleep(0.2)


def measure_edit_latency(pg, api: httpx.Client, pid: str) -> dict:
    """From the release of a threshold line / an edit click to the new revision drawn (ms):
    threshold commits lowering, raising back and lowering again (each refinement waited for before
    the next), with the pyramids each rebuilt."""
    out = {}
    pg.click("[data-testid=zoom-fit]")
    thr = state(pg)["thresholds"]["loudness"]
    commits = []
    for value in (thr - 0.2, thr, thr - 0.1, thr + 0.1, thr):
        ms = drag_threshold(pg, "loudness", max(0.0, min(1.0, value)))
        commits.append({"to": round(value, 3), "ms": round(ms, 1), "pyramids_built": state(pg)["pyramidsBuilt"]})
        wait_no_job(api, pid)
        pg.wait_for_function("(r) => window.autohaptics.state().drawnRevision >= r",
                             arg=api.get(f"/api/projects/{pid}").json()["revision"], timeout=60_000)
    out["threshold_commits"] = commits
    out["threshold_commit_to_redraw_ms"] = summary([c["ms"] for c in commits])
    s1 = state(pg)
    pg.evaluate("() => { document.querySelector('[data-testid=video]').currentTime = 60; }")
    wave = pg.evaluate("() => window.autohaptics.laneRect('actuators')")
    x0 = pg.evaluate("() => window.autohaptics.clientXOf(3600)")
    x1 = pg.evaluate("() => window.autohaptics.clientXOf(3900)")
    pg.mouse.move(x0, wave["y"] + 5)
    pg.mouse.down()
    pg.mouse.move(x1, wave["y"] + 5, steps=4)
    pg.mouse.up()
    t0 = pg.evaluate("() => performance.now()")
    pg.click("[data-testid=edit-clear]")
    wait_revision_above(pg, s1["revision"])
    out["edit_to_redraw_ms"] = pg.evaluate("() => performance.now()") - t0
    return out


def js_heap_mb(pg) -> float:
    """The editor page's used JS heap (Chrome DevTools Protocol), MiB."""
    cdp = pg.context.new_cdp_session(pg)
    cdp.send("Performance.enable")
    metrics = {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}
    return metrics["JSHeapUsedSize"] / 2**20


def server_rss_mb(proc) -> float:
    """RSS of the server and its job workers, MiB."""
    import psutil

    p = psutil.Process(proc.pid)
    return sum(q.memory_info().rss for q in [p, *p.children(recursive=True)]) / 2**20


def summary(values: list[float]) -> dict:
    if not values:
        return {}
    v = sorted(values)
    return {"median": round(statistics.median(v), 1), "min": round(v[0], 1), "max": round(v[-1], 1)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=5, help="editor openings to time (default 5)")
    ap.add_argument("--seconds", type=float, default=8.0, help="seconds of playback per view (default 8)")
    args = ap.parse_args(argv)
    from playwright.sync_api import sync_playwright

    proc, url = start_server(BENCH_DIR / "server")
    try:
        with api_client(url, timeout=300.0) as api:
            project = ensure_project(api)
        pid = project["id"]
        print(f"project {pid}: {project['n_ticks']} ticks ({project['duration_s'] / 3600:.2f} h)", flush=True)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=str(CHROMIUM), headless=True, args=CHROMIUM_ARGS)
            results = {"n_ticks": project["n_ticks"], "chromium": browser.version,
                       "open": measure_open(browser, url, pid, args.runs)}
            ctx = browser.new_context(viewport=VIEWPORT, base_url=url)
            pg = ctx.new_page()
            open_editor(pg, pid)
            pg.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 2")
            results["playback"] = [measure_playback(pg, args.seconds, s)
                                   for s in ("fit", "zoomed-follow", "fit-panning")]
            with httpx.Client(base_url=url, timeout=300.0) as api:
                results["editing"] = measure_edit_latency(pg, api, pid)
            results["js_heap_mb"] = js_heap_mb(pg)
            results["server_rss_mb"] = server_rss_mb(proc)
            ctx.close()
            browser.close()
    finally:
        stop_server(proc)
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=1))
    report(results)
    return 0


def report(r: dict) -> None:
    o = r["open"]
    print(f"\nEditor on a {r['n_ticks']}-tick timeline (Chromium {r['chromium']}, headless, software rendering)")
    print(f"  first render, opened from the list : {fmt(o['first_render_from_list_ms'])}  (target < 1000 ms)")
    st = o["from_list_steps_ms"]
    print(f"      after the click (medians): timeline.bin in at {st['binFetched']['median']:.0f} ms, parsed with "
          f"pyramids at {st['dataLoaded']['median']:.0f} ms, every lane drawn at {st['firstRender']['median']:.0f} ms")
    print(f"  first render, project URL (cold)   : {fmt(o['first_render_cold_url_ms'])}  (from navigation start)")
    print(f"  timeline.bin                       : {o['timeline_bin_bytes'] / 2**20:.1f} MiB, "
          f"request {fmt(o['timeline_bin_request_ms'])} (cold loads)")
    print("  playback (ms per frame: work = editor's frame callbacks, interval = between frames)")
    for p in r["playback"]:
        w, i = p["work"], p["interval"]
        print(f"    {p['scenario']:<14} {p['px_per_s']:>9.3f} px/s  frames {w['n']:>4}  redraws {p['lane_redraws']:>4}  "
              f"work p50 {w['p50']:.2f} p95 {w['p95']:.2f} max {w['max']:.2f}  "
              f"interval p50 {i['p50']:.1f} p95 {i['p95']:.1f}  (target work p95 < 16 ms)")
    e = r["editing"]
    print(f"  threshold release -> redrawn : {fmt(e['threshold_commit_to_redraw_ms'])}  (target <= 200 ms; "
          "per commit: " + ", ".join(f"{c['to']}: {c['ms']:.0f} ms, {c['pyramids_built']} pyramids"
                                     for c in e["threshold_commits"]) + ")")
    print(f"  edit click -> redrawn        : {e['edit_to_redraw_ms']:.0f} ms")
    print(f"  with the project open: editor JS heap {r['js_heap_mb']:.0f} MiB, server RSS {r['server_rss_mb']:.0f} MiB")
    print(f"  (written to {RESULTS.relative_to(REPO)})")


def fmt(s: dict) -> str:
    return f"median {s['median']:.0f} ms (min {s['min']:.0f}, max {s['max']:.0f})" if s else "n/a"


if __name__ == "__main__":
    sys.exit(main())
