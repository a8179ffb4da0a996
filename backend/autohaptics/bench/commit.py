"""``autohaptics bench commit``: threshold commits on a long film through a real ``autohaptics serve``.

Uploads FILM (by default a 2-hour 64 x 36, 5 fps film with events over silence, written once into
the work folder) to a private server, lets it generate, then commits thresholds as the editor does
and prints, per commit: PUT /params, then GET of the composed timeline.bin it leads to (gzip, as
a browser asks, with ``?since=`` the revision held: the blocks that changed), their sum (target <= 150 ms) and the server's CPU time over both (the steadier
figure on a shared machine), the bytes sent, whether a refinement started (a threshold wakes none:
the analysis has the saliency of every tick the sliders could wake) and its wall time as a share of
the first generate (target <= 10 %). Then it lowers the loudness gate, which wakes ticks without
saliency, stops the server while that refinement runs, starts it again and prints what the project
shows (target: never ``failed``, the parameters kept, the job done again) and the job's share. The server's RSS is printed with the project open.
Figures are printed (and written as JSON), never asserted.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import time
from pathlib import Path

import httpx
import psutil

from autohaptics.bench.common import table
from autohaptics.bench.serve import start_server as serve
from autohaptics.bench.serve import stop_server

NAME = "bench commit"
RAISE = {"loudness": 0.95, "sharpness": 0.95, "booming": 0.95, "low_energy": 0.95}
# Successively lower thresholds: each wakes ticks that the ones before left still.
LOWER = [{"loudness": v, "sharpness": v - 0.1, "booming": v - 0.05, "low_energy": v} for v in (0.7, 0.6, 0.5, 0.4)]
RESTART = {"loudness": 0.3, "sharpness": 0.2, "booming": 0.25, "low_energy": 0.3}
# The analysis holds the saliency of every tick the thresholds could wake; a loudness gate below the
# analysed one (default 0.2) wakes ticks without it: the refinement the restart interrupts.
RESTART_GATE = {"intensity.loudness_gate": 0.02}


def register(sub) -> None:
    p = sub.add_parser("commit", help="threshold commits on a 2-hour film through the API: answer time, "
                                      "refinement cost, a restart mid-refinement",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("film", nargs="?", default=None, help="media file (default: write the 2-hour film)")
    p.add_argument("--work", default="/tmp/autohaptics-bench-commit",
                   help="folder for the written film, the server's data and the JSON (default %(default)s); a "
                        "project generated there is reused, but its lowering figures hold only on its first run")
    p.add_argument("--hours", type=float, default=2.0, help="length of the written film (default 2)")
    p.add_argument("--bed", action="store_true",
                   help="write the other film: events over a steady bed of tone and room noise, other colours")
    p.add_argument("--floor-db", type=float, default=None,
                   help="write the film over a white noise floor at this level (dBFS RMS, e.g. -100) "
                        "instead of exact digital silence")
    p.add_argument("--repeat", type=int, default=5, help="answer-time measurements of each commit (default 5)")
    p.set_defaults(func=run)


def write_film(path: Path, duration_s: float = 7200.0, *, bed: bool = False, floor_db: float | None = None) -> Path:
    """A ``duration_s`` film at 64 x 36, 5 fps: 45 s textured colour segments, every 9-13 s a
    bright disc (left or right) with, alternately, a low tone or pink noise, over silence; with
    ``bed`` over a steady 220 Hz tone and pink room noise, in other colours, the discs high or low;
    with ``floor_db`` (dBFS RMS) over a white noise floor (:func:`~autohaptics.testing.sounds.noise_floor`;
    -100 survives the AAC encoding) instead of exact digital silence, the pictures the same."""
    from autohaptics.testing import Noise, Scene, Segment, Shape, Texture, Tone, write_scene
    from autohaptics.testing.sounds import noise_floor

    colours = [(40, 45, 60), (170, 60, 40), (50, 140, 70), (60, 80, 160)]
    if bed:
        colours = [(200, 150, 90), (30, 30, 35), (90, 170, 190), (150, 90, 150)]
    segments = tuple(Segment(t, min(duration_s, t + 45.0), colours[i % 4], texture=Texture("noise", 0.1, 0.3, seed=i % 5))
                     for i, t in enumerate(float(s) for s in range(0, int(duration_s), 45)))
    shapes, audio = [], []
    t, k = 3.0, 0
    while t + 4 < duration_s:
        at = (0.5, 0.25 if k % 2 else 0.75) if bed else (0.2 if k % 2 else 0.8, 0.5)
        shapes.append(Shape("circle", (250, 250, 240), t_on=t - 0.5, t_off=t + 3.0, xy0=at, size0=(0.2, 0.35)))
        if k % 2 == 0:
            audio.append(Tone(t, t + 1.2, 45.0 + 10 * (k % 4), level_dbfs=-12.0 - (k % 9) * 2, ramp_s=0.05))
        else:
            audio.append(Noise(t, t + 2.0, level_dbfs=-18.0 - (k % 7) * 2, colour="pink", seed=k, ramp_s=0.1))
        t += 9.0 + (k % 5)
        k += 1
    if bed:
        audio += [Tone(0.0, duration_s, 220.0, level_dbfs=-30.0), Noise(0.0, duration_s, level_dbfs=-42.0, colour="pink", seed=99)]
    if floor_db is not None:
        audio.append(noise_floor(duration_s, floor_db))
    scene = Scene(duration_s, background=segments, shapes=tuple(shapes), audio=tuple(audio), name="bench-commit")
    return write_scene(path, scene, width=64, height=36, fps=5, long=True, quality="low", sample_rate=24000)


def start_server(data: Path) -> tuple[subprocess.Popen, str]:
    """``autohaptics serve`` on a free port with ``data`` (its log appended to ``data/server.log``)."""
    data.mkdir(parents=True, exist_ok=True)
    return serve(data, log_path=data / "server.log", timeout_s=120.0)


def wait_job(api: httpx.Client, job_id: str, timeout_s: float = 3600.0) -> dict:
    deadline = time.monotonic() + timeout_s
    while True:
        job = api.get(f"/api/jobs/{job_id}").json()
        if job["status"] in ("done", "failed", "cancelled") or time.monotonic() > deadline:
            return job
        time.sleep(0.25)


def job_seconds(job: dict) -> float | None:
    """Wall time of a finished job from its record, s."""
    from datetime import datetime

    if not (job.get("started_at") and job.get("finished_at")):
        return None
    return (datetime.fromisoformat(job["finished_at"]) - datetime.fromisoformat(job["started_at"])).total_seconds()


def ensure_project(api: httpx.Client, film: Path, work: Path) -> tuple[dict, float]:
    """The generated project of ``film`` (reused when there) and its first generate's wall time, s."""
    record = work / "first_generate.json"
    for p in api.get("/api/projects").json():
        if p["name"] == NAME and p["status"] == "ready" and record.exists():
            return p, float(json.loads(record.read_text())["seconds"])
    print(f"uploading {film} and generating (the real pipeline) …", flush=True)
    with open(film, "rb") as fh:
        r = api.post("/api/projects", files={"file": (film.name, fh)}, data={"name": NAME, "mode": "multimodal"})
    r.raise_for_status()
    job = wait_job(api, r.json()["job"]["id"])
    if job["status"] != "done":
        raise SystemExit(f"generation failed: {job}")
    seconds = job_seconds(job) or float("nan")
    record.write_text(json.dumps({"seconds": seconds}))
    print(f"  first generate {seconds:.1f} s", flush=True)
    return api.get(f"/api/projects/{r.json()['id']}").json(), seconds


def commit(api: httpx.Client, pid: str, thresholds: dict, server: psutil.Process, held: list[int]) -> dict:
    """One commit as the editor makes it: PUT /params, then GET the composed timeline.bin (gzip)
    with what changed since the revision it holds (``held[0]``, moved on to the answer's); with
    the server process's CPU time over both (steadier than wall time on a loaded machine)."""
    c0 = sum(server.cpu_times()[:2])
    t0 = time.perf_counter()
    r = api.put(f"/api/projects/{pid}/params", json={"thresholds": thresholds})
    t1 = time.perf_counter()
    r.raise_for_status()
    b = api.get(f"/api/projects/{pid}/timeline.bin", params={"since": held[0]}, headers={"Accept-Encoding": "gzip"})
    t2 = time.perf_counter()
    b.raise_for_status()
    held[0] = r.json()["revision"]
    return {"put_ms": (t1 - t0) * 1e3, "bin_ms": (t2 - t1) * 1e3, "total_ms": (t2 - t0) * 1e3,
            "cpu_ms": (sum(server.cpu_times()[:2]) - c0) * 1e3, "bytes": b.num_bytes_downloaded,
            "job": r.json()["job"]}


def commit_rows(api: httpx.Client, pid: str, repeat: int, first_s: float, server: psutil.Process) -> list[dict]:
    """Raise and restore ``repeat`` times each (neither wakes a tick without saliency), then each
    lowering of :data:`LOWER` once with its refinement waited for."""
    project = api.get(f"/api/projects/{pid}").json()
    base, held = project["params"]["thresholds"], [project["revision"]]
    api.get(f"/api/projects/{pid}/timeline.bin", headers={"Accept-Encoding": "gzip"})  # what the editor opened
    runs = {"raise": [], "restore": []}
    for _ in range(repeat):
        runs["raise"].append(commit(api, pid, RAISE, server, held))
        runs["restore"].append(commit(api, pid, base, server, held))
    keys = ("put_ms", "bin_ms", "total_ms", "cpu_ms")
    rows = [dict(case=name, **{k: statistics.median(r[k] for r in rs) for k in keys},
                 bytes=rs[-1]["bytes"], jobs=sum(bool(r["job"]) for r in rs), job_s=0.0, share=0.0)
            for name, rs in runs.items()]
    for th in LOWER:
        r = commit(api, pid, th, server, held)
        job = wait_job(api, r["job"]["id"]) if r["job"] else None
        seconds = (job_seconds(job) or float("nan")) if job else 0.0
        if job is not None:  # the refinement's own revision: the editor reloads it whole
            held[0] = api.get(f"/api/projects/{pid}").json()["revision"]
            api.get(f"/api/projects/{pid}/timeline.bin", headers={"Accept-Encoding": "gzip"})
        rows.append(dict(case=f"lower to loudness {th['loudness']}", put_ms=r["put_ms"], bin_ms=r["bin_ms"],
                         total_ms=r["total_ms"], cpu_ms=r["cpu_ms"], bytes=r["bytes"], jobs=int(job is not None),
                         job_s=seconds,
                         share=seconds / first_s, status=job and job["status"]))
    return rows


def server_rss_mb(proc: subprocess.Popen) -> float:
    """RSS of the server and its job workers, MiB."""
    p = psutil.Process(proc.pid)
    return sum(q.memory_info().rss for q in [p, *p.children(recursive=True)]) / 2**20


def restart_mid_refinement(api: httpx.Client, proc: subprocess.Popen, data: Path, pid: str, first_s: float):
    """Lower the thresholds and the loudness gate, stop the server while the refinement runs, start
    it again: what the project shows, whether the parameters were kept, and the job's end (its share
    of the first generate). Returns (row, proc, api)."""
    r = api.put(f"/api/projects/{pid}/params", json={"thresholds": RESTART, "overrides": RESTART_GATE}).json()
    job_id = r["job"]["id"] if r["job"] else None
    while job_id and api.get(f"/api/jobs/{job_id}").json()["status"] == "queued":
        time.sleep(0.05)
    time.sleep(1.0)
    before = api.get(f"/api/jobs/{job_id}").json() if job_id else None
    stop_server(proc)
    t0 = time.perf_counter()
    proc, url = start_server(data)
    api = httpx.Client(base_url=url, timeout=120)
    up_s = time.perf_counter() - t0
    project = api.get(f"/api/projects/{pid}").json()
    row = {"job_before_stop": before and f"{before['status']} {before['stage']} {before['progress']:.2f}",
           "server_up_s": up_s, "status_after_start": project["status"],
           "params_kept": project["params"]["thresholds"] == RESTART and project["params"]["overrides"] == RESTART_GATE,
           "has_timeline": project["has_timeline"]}
    if job_id:
        job = wait_job(api, job_id)
        row.update(job_after=job["status"], job_s=job_seconds(job), share=(job_seconds(job) or 0.0) / first_s)
    row["status_at_end"] = api.get(f"/api/projects/{pid}").json()["status"]
    return row, proc, api


def run(args) -> int:
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    floor = "" if args.floor_db is None else f"-floor{args.floor_db:g}"
    film = Path(args.film) if args.film else work / f"film-{args.hours:g}h-64x36-5fps{'-bed' if args.bed else ''}{floor}.mp4"
    if not film.exists():
        print(f"writing {film} …", flush=True)
        write_film(film, args.hours * 3600.0, bed=args.bed, floor_db=args.floor_db)
    proc, url = start_server(work / "data")
    try:
        api = httpx.Client(base_url=url, timeout=600)
        project, first_s = ensure_project(api, film, work)
        pid = project["id"]
        print(f"{project['n_ticks']} ticks; first generate {first_s:.1f} s", flush=True)
        rows = commit_rows(api, pid, args.repeat, first_s, psutil.Process(proc.pid))
        rss = server_rss_mb(proc)
        restart, proc, api = restart_mid_refinement(api, proc, work / "data", pid, first_s)
    finally:
        stop_server(proc)
    print(table([[r["case"], r["put_ms"], r["bin_ms"], r["total_ms"], r["cpu_ms"], r["bytes"], r["jobs"], r["job_s"],
                  100 * r["share"]] for r in rows],
                ["commit", "PUT ms", "timeline.bin ms", "sum ms", "server CPU ms", "bytes sent", "jobs", "job s", "% of first"]))
    print(f"server RSS with the project open: {rss:.0f} MiB")
    print("restart mid-refinement: " + ", ".join(f"{k} {v if not isinstance(v, float) else round(v, 3)}"
                                                 for k, v in restart.items()))
    out = {"film": str(film), "n_ticks": project["n_ticks"], "first_generate_s": first_s, "commits": rows,
           "server_rss_mb": rss, "restart": restart}
    (work / "bench_commit.json").write_text(json.dumps(out, indent=1, default=str))
    print(f"figures in {work / 'bench_commit.json'}")
    return 0
