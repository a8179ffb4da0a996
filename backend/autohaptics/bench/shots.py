"""``autohaptics bench shots``: the shot list of a long film through a real ``autohaptics serve``.

Writes (once, into the work folder) a film of ``--hours`` at 64 x 36, 5 fps whose shots change
every ``--shot-s`` seconds (default 3.6: 2,000 shots in 2 hours; each boundary 0.1 s after a
multiple of it, so none falls on a frame's instant): hard cuts, every 5th boundary a 1 s
cross-dissolve, every 7th a fade through black. A private server generates it (a project already
generated in the work folder is reused), then the bench prints the answer times of
``GET /api/projects/{id}/shots`` (target <= 300 ms): the first after the generate, the same
revision again (median of ``--repeat``), the first after a threshold commit (new summaries over
the same boundaries), after a ``shot_split`` edit, all with the project open (its timeline.bin fetched first, the
server's memory settled); the server's RSS with the project closed, open, and after the shots; the first
screen of posters (20 mid-film shots, made on demand while the background maker runs, then again
from the disk cache); filmstrip tiles on demand; a shot's similar shots (first and again); one
``group`` of ``scale`` ops over the 300 shots nearest a shot (target <= 150 ms) and its undo; the
time until every poster and the coarse filmstrip are made ahead, and the picture cache's size on
disk (target <= 100 MB; the pictures of an earlier run are removed first); and the boundaries
found against the film's own (precision and recall within one tick, and within two: one frame at
5 fps). Figures are printed (and written as JSON), never asserted.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import time
from pathlib import Path

import httpx

from autohaptics.bench.commit import job_seconds, server_rss_mb, wait_job
from autohaptics.bench.serve import start_server, stop_server

NAME = "bench-shots"


def register(sub) -> None:
    p = sub.add_parser("shots", help="the shot list of a 2-hour film through the API: answer times, detection",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--work", default="/tmp/autohaptics-bench-shots", help="folder for the film, the server's data "
                                                                          "and the JSON (default %(default)s)")
    p.add_argument("--hours", type=float, default=2.0, help="length of the written film (default 2)")
    p.add_argument("--shot-s", type=float, default=3.6, help="seconds between boundaries (default 3.6)")
    p.add_argument("--repeat", type=int, default=5, help="answers timed per case (default 5)")
    p.set_defaults(func=run)


def write_film(path: Path, duration_s: float, shot_s: float, *, write: bool = True
               ) -> tuple[Path, list[tuple[int, str]]]:
    """The film (written unless ``write`` is False) and its boundaries [(tick, kind)] (a fade's
    tick is its black's middle)."""
    from autohaptics.testing import Scene, write_scene

    segs, truth = shot_segments(duration_s, shot_s)
    scene = Scene(duration_s, background=segs, name=NAME)
    if not write:
        return path, truth
    return write_scene(path, scene, width=64, height=36, fps=5, long=True, quality="low", audio=True,
                       sample_rate=24000), truth


def shot_segments(duration_s: float, shot_s: float) -> tuple[tuple, list[tuple[int, str]]]:
    """The background segments of a film whose shots change every ``shot_s`` seconds (hard cuts,
    every 5th a 1 s dissolve, every 7th a fade through black) and its boundaries [(tick, kind)]."""
    from autohaptics.testing import Segment, Texture

    colours = [(40, 60, 150), (170, 70, 40), (50, 150, 70), (140, 140, 140), (150, 60, 140), (200, 180, 70)]
    segs, truth, t, i = [], [], 0.0, 0
    while t < duration_s - 1e-9:  # boundaries 0.1 s after a multiple of shot_s: between two frames' instants
        end = min(duration_s, round((i + 1) * shot_s + 0.1, 6))
        tex = Texture("noise", 0.1, 0.45, seed=i % 7)
        colour = colours[i % len(colours)]
        if i and i % 7 == 0 and end - t > 2.0:  # a fade in from black; the shot before faded out
            prev = segs.pop()
            segs += [Segment(prev.t0, t - 0.5, prev.rgb, texture=prev.texture, dissolve_s=prev.dissolve_s),
                     Segment(t - 0.5, t, prev.rgb, rgb_end=(0, 0, 0), texture=prev.texture),
                     Segment(t, t + 0.5, (0, 0, 0), rgb_end=colour, texture=tex)]
            segs.append(Segment(t + 0.5, end, colour, texture=tex))
            truth.append((round(t * 10), "fade"))
        else:
            dissolve = 1.0 if i and i % 5 == 0 else 0.0
            segs.append(Segment(t, end, colour, texture=tex, dissolve_s=dissolve))
            if i:
                truth.append((round(t * 10), "dissolve" if dissolve else "cut"))
        t, i = end, i + 1
    return tuple(segs), truth


def _project(api: httpx.Client, film: Path) -> tuple[str, dict | None]:
    """The generated project of ``film`` (reused when the data folder has it; its job then None)."""
    for p in api.get("/api/projects").json():
        if p["name"] == NAME and p["status"] == "ready":
            return p["id"], None
    with open(film, "rb") as fh:
        r = api.post("/api/projects", files={"file": (film.name, fh)}, data={"name": NAME})
    r.raise_for_status()
    job = wait_job(api, r.json()["job"]["id"])
    if job["status"] != "done":
        raise SystemExit(f"generation failed: {job}")
    return r.json()["id"], job


def settled_rss(proc, *, wait_s: float = 30.0) -> float:
    """The server's RSS, MiB, once three samples 0.5 s apart agree within 2 MiB (at most ``wait_s``)."""
    samples = [server_rss_mb(proc)]
    deadline = time.monotonic() + wait_s
    while time.monotonic() < deadline and (len(samples) < 3 or max(samples[-3:]) - min(samples[-3:]) > 2.0):
        time.sleep(0.5)
        samples.append(server_rss_mb(proc))
    return samples[-1]


def _timed(api: httpx.Client, method: str, url: str, **kw) -> tuple[float, httpx.Response]:
    t0 = time.perf_counter()
    r = api.request(method, url, **kw)
    r.raise_for_status()
    return 1000 * (time.perf_counter() - t0), r


def run(args) -> int:
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    film = work / f"shots-{args.hours:g}h-{args.shot_s:g}s.mp4"
    print(f"film {film} …", flush=True)
    film, truth = write_film(film, args.hours * 3600.0, args.shot_s, write=not film.exists())
    data = work / f"data-{film.stem}"
    for folder in [*data.glob("projects/*/posters"), *data.glob("projects/*/filmstrip")]:
        shutil.rmtree(folder)  # the pictures are made again, ahead and on demand
    proc, url = start_server(data, log_path=work / "server.log", timeout_s=120.0)
    try:
        api = httpx.Client(base_url=url, timeout=600)
        pid, job = _project(api, film)
        rss_closed = server_rss_mb(proc)
        t_open = time.perf_counter()
        open_ms, _ = _timed(api, "GET", f"/api/projects/{pid}/timeline.bin")  # the editor opens the project
        rss0 = settled_rss(proc)  # the server warms the analysis for the first commit in the background
        first, answer = _timed(api, "GET", f"/api/projects/{pid}/shots")
        doc = answer.json()
        screen = doc["shots"][len(doc["shots"]) // 2:][:20]  # a first screen of posters, mid-film, made now
        t0 = time.perf_counter()
        poster_ms = [_timed(api, "GET", s["poster_url"])[0] for s in screen]
        screen_ms = 1000 * (time.perf_counter() - t0)
        cached_ms = statistics.median(_timed(api, "GET", s["poster_url"])[0] for s in screen)
        strip = _filmstrip(api, pid)
        similar = _similar_and_group(api, pid, doc, args.repeat)
        again = statistics.median(_timed(api, "GET", f"/api/projects/{pid}/shots")[0] for _ in range(args.repeat))
        loud = api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["loudness"]
        other = 0.6 if loud == 0.5 else 0.5
        _timed(api, "PUT", f"/api/projects/{pid}/params", json={"thresholds": {"loudness": other}})
        after_commit, answer = _timed(api, "GET", f"/api/projects/{pid}/shots")
        doc2 = answer.json()
        rev = api.get(f"/api/projects/{pid}").json()["revision"]
        third = doc["shots"][len(doc["shots"]) // 3]
        split_at = (third["t0"] + third["t1"]) // 2  # inside it: every shot is 2 ticks or longer
        split_ms, _ = _timed(api, "POST", f"/api/projects/{pid}/edits",
                             json={"base_revision": rev, "op": {"op": "shot_split", "t": split_at}})
        after_split, _ = _timed(api, "GET", f"/api/projects/{pid}/shots")
        rss1 = server_rss_mb(proc)
        ahead = _made_ahead(data / "projects" / pid, len(doc["shots"]), t_open)
        ahead["rss_after_pictures_mb"] = server_rss_mb(proc)
    finally:
        stop_server(proc)
    found = [s["t0"] for s in doc["shots"][1:] if s["kind"] != "split"]  # an earlier run's split is no find
    hits = _matches(found, [t for t, _ in truth])
    hits2 = _matches(found, [t for t, _ in truth], tol=2)  # one frame at 5 fps
    same = [(s["t0"], s["t1"]) for s in doc["shots"]] == [(s["t0"], s["t1"]) for s in doc2["shots"]]
    out = {"film": str(film), "shots": len(doc["shots"]), "found": len(found), "truth": len(truth),
           "precision": hits / max(1, len(found)),
           "recall": hits / max(1, len(truth)),
           "precision_2": hits2 / max(1, len(found)), "recall_2": hits2 / max(1, len(truth)),
           "first_ms": first, "again_ms": again, "after_commit_ms": after_commit,
           "boundaries_kept_by_commit": same, "split_ms": split_ms, "after_split_ms": after_split,
           "open_ms": open_ms, "rss_closed_mb": rss_closed, "rss_open_mb": rss0, "rss_after_mb": rss1,
           "generate_s": job_seconds(job) if job else None,
           "posters": len(screen), "poster_first_ms_median": statistics.median(poster_ms),
           "poster_first_ms_max": max(poster_ms), "posters_screen_ms": screen_ms, "poster_cached_ms": cached_ms,
           **strip, **similar, **ahead}
    for k, v in out.items():
        print(f"{k}: {round(v, 3) if isinstance(v, float) else v}")
    (work / "bench_shots.json").write_text(json.dumps(out, indent=1))
    return 0


def _filmstrip(api: httpx.Client, pid: str) -> dict:
    """The filmstrip's geometry, and tiles on demand mid-film at a fine, a middle and the coarsest step."""
    ms, r = _timed(api, "GET", f"/api/projects/{pid}/filmstrip")
    geo = r.json()
    out = {"filmstrip_ms": ms, "filmstrip_steps": len(geo["steps"]), "frame_w": geo["frame_w"]}
    n = api.get(f"/api/projects/{pid}/shots").json()["n_ticks"]
    for step in (1, 16, geo["steps"][-1]):
        tile = (n // (16 * step)) // 2
        out[f"tile_step{step}_ms"], r = _timed(api, "GET", f"/api/projects/{pid}/filmstrip/{step}/{tile}.jpg")
        out[f"tile_step{step}_kb"] = len(r.content) / 1024
    return out


def _similar_and_group(api: httpx.Client, pid: str, doc: dict, repeat: int) -> dict:
    """A mid-film shot's similar shots (first: the features are computed; then again, other shots),
    one ``group`` scaling the 300 nearest shots' vibration, the shot list after it, and its undo."""
    shots = doc["shots"]
    mid = shots[len(shots) // 2]["id"]
    first, r = _timed(api, "GET", f"/api/projects/{pid}/shots/{mid}/similar")
    near = r.json()["similar"][:300]
    again = statistics.median(_timed(api, "GET", f"/api/projects/{pid}/shots/{s['id']}/similar")[0]
                              for s in shots[:repeat])
    ends = {s["id"]: s["t1"] for s in shots}
    ops = [{"op": "scale", "lanes": ["A1", "A2", "A5"], "t0": s["id"], "t1": ends[s["id"]], "factor": 0.5}
           for s in near]
    rev = api.get(f"/api/projects/{pid}").json()["revision"]
    group_ms, r = _timed(api, "POST", f"/api/projects/{pid}/edits",
                         json={"base_revision": rev, "op": {"op": "group", "ops": ops}})
    after_group, _ = _timed(api, "GET", f"/api/projects/{pid}/shots")
    undo_ms, _ = _timed(api, "POST", f"/api/projects/{pid}/undo", json={"base_revision": r.json()["revision"]})
    return {"similar_first_ms": first, "similar_again_ms": again, "similar_picked": len(near),
            "similar_distance_300th": near[-1]["distance"], "group_ops": len(ops), "group_ms": group_ms,
            "after_group_shots_ms": after_group, "undo_group_ms": undo_ms}


def _made_ahead(folder: Path, n_shots: int, t_open: float, *, wait_s: float = 900.0) -> dict:
    """Seconds from the open until every shot's poster is on disk (the background maker does the coarse
    filmstrip first), and the picture cache's size then."""
    deadline = time.perf_counter() + wait_s
    count = 0
    while time.perf_counter() < deadline:
        count = len(list((folder / "posters").glob("*.jpg")))
        if count >= n_shots:
            break
        time.sleep(1.0)
    files = [p for d in ("posters", "filmstrip") for p in (folder / d).glob("*.jpg")]
    return {"ahead_posters": count, "ahead_all_s": time.perf_counter() - t_open,
            "ahead_tiles": len(list((folder / "filmstrip").glob("*.jpg"))),
            "picture_cache_mb": sum(p.stat().st_size for p in files) / 2**20}


def _matches(found: list[int], truth: list[int], tol: int = 1) -> int:
    """One-to-one matches within ``tol`` ticks."""
    free = sorted(truth)
    hits = 0
    for t in sorted(found):
        near = [u for u in free if abs(u - t) <= tol]
        if near:
            free.remove(near[0])
            hits += 1
    return hits
