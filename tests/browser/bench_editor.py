"""Editor performance on a 2-hour film (72,000 ticks): a script that prints figures, not a test.

    .venv/bin/python tests/browser/bench_editor.py            # about 3 minutes the first time
    .venv/bin/python tests/browser/bench_editor.py --runs 10  # more opening runs

What it does, through the real service and Debian's Chromium:

1. Writes a 2-hour low-resolution film with sound and about 2,000 shots (autohaptics.testing and
   ``bench shots``' boundaries, cached in out/bench/), uploads it to a private ``autohaptics serve``
   and lets the real pipeline generate its timeline (the project is kept in out/bench/ and reused
   by later runs); when it generates, the first threshold commit after the job (``PAUSE_S`` later).
   A few edits give every lane content: temperature points across the film, fans in scenes, markers.
2. Opening, ``--runs`` times in fresh browser contexts, read from the editor's own marks: the
   time to the first complete draw of every lane (a) when the project is opened from the projects
   list (project, edits, timeline.bin, parsing, pyramids, drawing) and (b) when its URL is loaded
   cold, from navigation start (the page and its modules too); plus the size and request time of
   timeline.bin, and (cold) the time until the Shots lane's first screen of pictures is in.
3. Playback: plays the film for ``--seconds`` in three views and reads the frame loop's statistics:
   ``work`` = milliseconds spent in the editor's animation-frame callbacks per frame (the playhead,
   the chair diagram, the fan overlay and every lane redraw), ``interval`` = time between frames.
   Views: the whole film in view (playhead only), zoomed to 400 px/s with follow (the view pages
   every ~3 s of film), the whole film while the user pans with the wheel every frame (every
   lane redrawn every frame: the worst case), and zoomed in to the filmstrip's frames while the
   user scrolls it with the wheel on the Shots lane.
4. Editing latency: threshold commits, lowering and raising (PUT /params -> re-derive -> reload ->
   redraw), and one edit (POST /edits -> reload -> redraw), from the user's release to the new
   revision on screen; then the editor's JS heap and the server's RSS with the project open.
5. Shots (issue 33), through the API: ``GET /shots`` (the first answer, then again), the server's
   RSS before the first and after all the shot work, the pictures on disk, the first screen of
   pictures made by the server (the coarsest filmstrip tiles, else 16 posters), ``similar`` and a
   ``group`` op (a scale) on the 300 shots nearest a mid-film one, and its undo (one step back to
   the same timeline).

Targets: first render < 1 s (cold URL too), frame time p95 < 16 ms (filmstrip scrolling 8 ms),
threshold release -> redrawn <= 200 ms, GET /shots <= 300 ms, first screen of pictures <= 2 s,
RSS growth with shots <= 50 MB, pictures on disk <= 100 MB, an op on 300 shots <= 150 ms. Results
also go to test-artifacts/bench_editor.json.
"""

from __future__ import annotations

import argparse
import json
import os
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
SHOT_S = 3.6  # seconds between shot boundaries: 2,000 shots
PAUSE_S = 5.0  # the designer's pause between a job's end and the first threshold commit
BENCH_DIR = REPO / "out" / "bench"
FILM = BENCH_DIR / "film-2h-64x36-shots.mp4"
PROJECT_NAME = "bench 2 h shots"
SIMILAR_N = 300
FILMSTRIP_ZOOM_INS = 12  # from the whole film: about 30 px/s, the filmstrip's frames a few ticks apart
RESULTS = REPO / "test-artifacts" / "bench_editor.json"
VIEWPORT = {"width": 1440, "height": 900}


def write_film(path: Path) -> None:
    """A 2-hour scene: a shot every 3.6 s (``bench shots``' cuts, dissolves and fades), a boom, a
    blip or a whoosh every 7-10 s."""
    from autohaptics.bench.shots import shot_segments
    from autohaptics.testing import Noise, Scene, Tone, write_scene

    segments, _ = shot_segments(DURATION_S, SHOT_S)
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


def ensure_project(api: httpx.Client, timings: dict | None = None) -> dict:
    """The generated 2-hour project (created once, then reused); when it is generated now, the first
    threshold commit after its job goes to ``timings["first_commit_after_generate_ms"]`` (:func:`first_commit`)."""
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
    first_ms = first_commit(api, pid)
    if timings is not None:
        timings["first_commit_after_generate_ms"] = first_ms
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


def first_commit(api: httpx.Client, pid: str) -> float:
    """The editor's first threshold commit after the generate (ms): it loads the timeline as the
    job ends, the designer pauses ``PAUSE_S``, lowers the loudness threshold (PUT /params) and the
    editor fetches what changed (timeline.bin ``since`` its revision, gzipped)."""
    rev = api.get(f"/api/projects/{pid}").json()["revision"]
    api.get(f"/api/projects/{pid}/timeline.bin", params={"blocks": "vibration,temperature_c,fan_activity,features"})
    time.sleep(PAUSE_S)
    loud = api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["loudness"]
    t0 = time.perf_counter()
    r = api.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": round(loud - 0.05, 3)}})
    r.raise_for_status()
    api.get(f"/api/projects/{pid}/timeline.bin", params={"since": rev}).raise_for_status()
    ms = 1000 * (time.perf_counter() - t0)
    print(f"  first threshold commit {PAUSE_S:.0f} s after the job: {ms:.0f} ms (job: {r.json()['job']})", flush=True)
    return ms


def measure_open(browser, url: str, pid: str, runs: int) -> dict:
    """Fresh browser context per run (cold cache). Two ways in: the project's URL typed or
    reloaded (page, modules and data load together), and a click on the project in the projects
    list (the modules are loaded; what the designer does most)."""
    cold, from_list, steps, bin_ms, bin_bytes, pictures = [], [], [], [], 0, []
    for _ in range(runs):
        ctx = browser.new_context(viewport=VIEWPORT, base_url=url)
        pg = ctx.new_page()
        pg.goto(f"/#/project/{pid}")
        pg.wait_for_selector("#app[data-ready='true']", timeout=60_000)
        t = state(pg)["timing"]
        cold.append(t["start"] + t["firstRender"])
        if (ms := pictures_in(pg)) is not None:
            pictures.append(ms)
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
        "pictures_first_screen_ms": summary(pictures),
    }


def pictures_in(pg, timeout_ms: float = 30_000) -> float | None:
    """When the Shots lane's first screen of pictures was in (ms from navigation start): the lane's
    picture cache holds some and loads none (None without a Shots lane, or not in ``timeout_ms``)."""
    if not (state(pg) or {}).get("shots"):
        return None
    try:
        return pg.wait_for_function("""() => {
            const p = window.autohaptics.state().shots.pictures;
            return p.ready > 0 && p.inFlight === 0 ? performance.now() : false; }""", timeout=timeout_ms).json_value()
    except Exception:  # noqa: BLE001 (playwright's TimeoutError)
        return None


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
    if scenario in ("fit-panning", "filmstrip-scroll"):
        for _ in range(2 if scenario == "fit-panning" else FILMSTRIP_ZOOM_INS):
            pg.click("[data-testid=zoom-in]")  # leave room to pan; the filmstrip: its frames one by one
        lane = pg.evaluate(f"() => window.autohaptics.laneRect('{'actuators' if scenario == 'fit-panning' else 'shots'}')")
        pg.mouse.move(lane["x"] + lane["width"] / 2, lane["y"] + 20)
        pg.evaluate("() => window.autohaptics.resetPerf()")
        direction = 1
        while time.perf_counter() - t0 < seconds:
            pg.mouse.wheel(0, 40 * direction)
            if scenario == "fit-panning":  # back and forth; the filmstrip scrolls on through new tiles
                direction = -direction
    else:
        pg.wait_for_timeout(seconds * 1000)
    stats = pg.evaluate("() => window.autohaptics.perf()")
    renders = pg.evaluate("() => window.autohaptics.renderCount()") - renders0
    s = state(pg)
    pg.click("[data-testid=play]")
    return {"scenario": scenario, "px_per_s": round(s["pxPerS"], 4), "lane_redraws": renders,
            "played_s": round(s["currentTime"] - 1800, 2), "filmstrip_step": (s.get("shots") or {}).get("step"),
            **stats}


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


def timed(api: httpx.Client, method: str, url: str, **kw) -> tuple[float, httpx.Response]:
    """(ms, response) of one request; fails on an error status."""
    t0 = time.perf_counter()
    r = api.request(method, url, **kw)
    ms = 1000 * (time.perf_counter() - t0)
    r.raise_for_status()
    return ms, r


def measure_shot_list(api: httpx.Client, pid: str, proc) -> dict:
    """With the project open (its timeline fetched, the server's memory settled): the first
    ``GET /shots`` and again (median of 5), the server's RSS before and after, and the first screen
    of pictures made by the server: the filmstrip tiles of the whole film at the coarsest step the
    editor shows at fit (frames about as wide as the lane / 16), else the posters of 16 shots spread
    over the film (ms for them all, asked one after the other)."""
    from autohaptics.bench.shots import settled_rss

    base = f"/api/projects/{pid}"
    api.get(f"{base}/timeline.bin", params={"blocks": "vibration,temperature_c,fan_activity,features"})
    rss_open = settled_rss(proc)
    first, answer = timed(api, "GET", f"{base}/shots")
    shots = answer.json()["shots"]
    again = statistics.median(timed(api, "GET", f"{base}/shots")[0] for _ in range(5))
    out = {"shots": len(shots), "first_ms": first, "again_ms": again, "rss_open_mb": rss_open,
           "rss_after_list_mb": server_rss_mb(proc)}
    strip = api.get(f"{base}/filmstrip")
    if strip.status_code == 200:
        step = strip.json()["steps"][-1]
        urls = [f"{base}/filmstrip/{step}/0.jpg"]
        out["first_screen"] = f"filmstrip step {step}, 1 tile"
    else:
        urls = [s["poster_url"] for s in shots[::max(1, len(shots) // 16)][:16]]
        out["first_screen"] = f"{len(urls)} posters"
    t0 = time.perf_counter()
    for u in urls:
        api.get(u).raise_for_status()
    out["first_screen_server_ms"] = 1000 * (time.perf_counter() - t0)
    return out


def measure_shot_op(api: httpx.Client, pid: str) -> dict:
    """``similar`` of a mid-film shot, then one ``group`` op scaling the vibration of the
    ``SIMILAR_N`` shots nearest it by 0.5 (answer time), and its undo (answer time; the timeline
    after it equal to the one before the op)."""
    base = f"/api/projects/{pid}"
    shots = api.get(f"{base}/shots").json()["shots"]
    mid = shots[len(shots) // 2]
    sim_ms, r = timed(api, "GET", f"{base}/shots/{mid['id']}/similar")
    chosen = {mid["id"], *(s["id"] for s in r.json()["similar"][:SIMILAR_N - 1])}
    ops = [{"op": "scale", "lanes": [f"A{k}" for k in range(1, 10)], "t0": s["t0"], "t1": s["t1"], "factor": 0.5}
           for s in shots if s["id"] in chosen]
    before = api.get(f"{base}/timeline.bin", headers={"Accept-Encoding": "identity"}).content
    rev = api.get(base).json()["revision"]
    op_ms, r = timed(api, "POST", f"{base}/edits", json={"base_revision": rev, "op": {"op": "group", "ops": ops}})
    rev_op = r.json()["revision"]
    changed = api.get(f"{base}/timeline.bin", headers={"Accept-Encoding": "identity"}).content
    undo_ms, r = timed(api, "POST", f"{base}/undo", json={"base_revision": rev_op})
    after = api.get(f"{base}/timeline.bin", headers={"Accept-Encoding": "identity"}).content
    same = _same_blocks(before, after)
    return {"similar_ms": sim_ms, "group_shots": len(ops), "group_op_ms": op_ms, "revision_steps": rev_op - rev,
            "op_changed_timeline": not _same_blocks(before, changed), "undo_ms": undo_ms,
            "undone_in_one_step": same}


def _same_blocks(a: bytes, b: bytes) -> bool:
    """Two binary timelines hold the same blocks (their headers' revisions aside)."""
    import numpy as np
    from autohaptics.timeline.wire import decode

    (_, x), (_, y) = decode(a), decode(b)
    return x.keys() == y.keys() and all(np.array_equal(x[k], y[k]) for k in x)


def picture_cache_mb(pid: str) -> float:
    """The project's pictures on disk (posters and filmstrip tiles), MB."""
    folder = BENCH_DIR / "server" / "data" / "projects" / pid
    return sum(p.stat().st_size for d in ("posters", "filmstrip") if (folder / d).is_dir()
               for p in (folder / d).rglob("*") if p.is_file()) / 1e6


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
            timings: dict = {"first_commit_after_generate_ms": None}
            project = ensure_project(api, timings)
            pid = project["id"]
            print(f"project {pid}: {project['n_ticks']} ticks ({project['duration_s'] / 3600:.2f} h)", flush=True)
            shots = measure_shot_list(api, pid, proc)
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path=str(CHROMIUM), headless=True, args=CHROMIUM_ARGS)
                results = {"n_ticks": project["n_ticks"], "chromium": browser.version, "load_start": os.getloadavg(),
                           **timings,
                           "open": measure_open(browser, url, pid, args.runs)}
                shots["rss_after_opens_mb"] = server_rss_mb(proc)
                ctx = browser.new_context(viewport=VIEWPORT, base_url=url)
                pg = ctx.new_page()
                open_editor(pg, pid)
                pg.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 2")
                views = ("fit", "zoomed-follow", "fit-panning") + (("filmstrip-scroll",) if state(pg).get("shots") else ())
                results["playback"] = [measure_playback(pg, args.seconds, s) for s in views]
                results["editing"] = measure_edit_latency(pg, api, pid)
                results["js_heap_mb"] = js_heap_mb(pg)
                results["server_rss_mb"] = server_rss_mb(proc)
                ctx.close()
                browser.close()
            try:
                shots.update(measure_shot_op(api, pid))
            except httpx.HTTPStatusError as exc:  # a server without similar shots or the group op
                shots["op_missing"] = f"{exc.response.status_code} {exc.request.url.path}"
            shots["rss_end_mb"] = server_rss_mb(proc)
            shots["picture_cache_mb"] = picture_cache_mb(pid)
            results["shots"] = shots
            results["load_end"] = os.getloadavg()
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
        target = 8 if p["scenario"] == "filmstrip-scroll" else 16
        step = f", filmstrip step {p['filmstrip_step']}" if p.get("filmstrip_step") else ""
        print(f"    {p['scenario']:<16} {p['px_per_s']:>9.3f} px/s  frames {w['n']:>4}  redraws {p['lane_redraws']:>4}  "
              f"work p50 {w['p50']:.2f} p95 {w['p95']:.2f} max {w['max']:.2f}  "
              f"interval p50 {i['p50']:.1f} p95 {i['p95']:.1f}  (target work p95 < {target} ms{step})")
    e = r["editing"]
    print(f"  threshold release -> redrawn : {fmt(e['threshold_commit_to_redraw_ms'])}  (target <= 200 ms; "
          "per commit: " + ", ".join(f"{c['to']}: {c['ms']:.0f} ms, {c['pyramids_built']} pyramids"
                                     for c in e["threshold_commits"]) + ")")
    print(f"  edit click -> redrawn        : {e['edit_to_redraw_ms']:.0f} ms")
    print(f"  with the project open: editor JS heap {r['js_heap_mb']:.0f} MiB, server RSS {r['server_rss_mb']:.0f} MiB")
    if r["first_commit_after_generate_ms"] is not None:
        print(f"  first threshold commit {PAUSE_S:.0f} s after the generate: {r['first_commit_after_generate_ms']:.0f} ms"
              "  (target <= 150 ms)")
    s = r["shots"]
    print(f"  shots ({s['shots']}): GET /shots first {s['first_ms']:.0f} ms, again {s['again_ms']:.0f} ms  (target <= 300 ms)")
    print(f"      first screen of pictures: in the editor {fmt(o['pictures_first_screen_ms'])} from navigation start "
          f"(target <= 2000 ms); made by the server ({s['first_screen']}) {s['first_screen_server_ms']:.0f} ms")
    if "op_missing" in s:
        print(f"      similar / group op: not served ({s['op_missing']})")
    else:
        print(f"      similar {s['similar_ms']:.0f} ms; group op on {s['group_shots']} shots {s['group_op_ms']:.0f} ms "
              f"(target <= 150 ms), {s['revision_steps']} revision, undo {s['undo_ms']:.0f} ms, "
              f"undone in one step: {s['undone_in_one_step']}")
    print(f"      server RSS: open {s['rss_open_mb']:.0f}, after GET /shots {s['rss_after_list_mb']:.0f}, after the opens "
          f"{s['rss_after_opens_mb']:.0f}, at the end {s['rss_end_mb']:.0f} MiB; pictures on disk "
          f"{s['picture_cache_mb']:.1f} MB (target <= 100)")
    print(f"  load average at the start {r['load_start']}, at the end {r['load_end']}")
    print(f"  (written to {RESULTS.relative_to(REPO)})")


def fmt(s: dict) -> str:
    return f"median {s['median']:.0f} ms (min {s['min']:.0f}, max {s['max']:.0f})" if s else "n/a"


if __name__ == "__main__":
    sys.exit(main())
