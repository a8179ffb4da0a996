"""Measured child processes: each configuration's ``generate`` and the bare decode run in a FRESH
process, so each peak memory is its own (``ru_maxrss`` from ``wait4``); the wall time is both the
whole process's and the ``generate`` call's own (after imports and a warm-up of the compiled audio
kernels, which a long film pays once)."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from autohaptics.errors import ParameterError

@dataclass
class ChildResult:
    returncode: int
    wall_s: float
    peak_rss_mb: float  # the child's own peak resident set size (ru_maxrss via wait4), MiB
    stdout: str
    stderr: str
    cpu_s: float = 0.0  # the child's user + system CPU seconds (wait4): steadier than wall on a shared machine


# A launcher of a few MB runs the measured command: a process's ru_maxrss starts at the RSS of the
# process it was forked from (Linux copies the page tables and keeps the high-water mark across
# exec), so a command started straight from this process would report at least this process's size.
_LAUNCHER = r"""
import json, os, sys, time
out, cmd = sys.argv[1], sys.argv[2:]
t0 = time.perf_counter()
pid = os.fork()
if pid == 0:
    try:
        os.execvp(cmd[0], cmd)
    finally:
        os._exit(127)
_, status, usage = os.wait4(pid, 0)
with open(out, "w") as fh:
    json.dump({"status": status, "maxrss_kb": usage.ru_maxrss, "wall_s": time.perf_counter() - t0,
               "cpu_s": usage.ru_utime + usage.ru_stime}, fh)
"""


def run_child(cmd: list[str], *, timeout_s: float | None = None, env: dict | None = None) -> ChildResult:
    """Run ``cmd`` in a fresh process: its exit code, wall time and its own peak RSS (``ru_maxrss``
    from ``wait4``, through a small launcher, so neither this process's size nor another child's
    counts). A run past ``timeout_s`` is killed with its launcher (returncode -9)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err, \
            tempfile.NamedTemporaryFile("r", suffix=".json") as res:
        proc = subprocess.Popen([sys.executable, "-I", "-S", "-c", _LAUNCHER, res.name, *cmd], stdout=out,
                                stderr=err, text=True, env=env, start_new_session=True)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, 9)
            proc.wait()
            out.seek(0)
            err.seek(0)
            return ChildResult(-9, float(timeout_s or 0.0), 0.0, out.read(), err.read())
        out.seek(0)
        err.seek(0)
        doc = json.loads(res.read() or "{}")
        if "status" not in doc:
            raise ParameterError(f"the measuring launcher failed (exit {proc.returncode}): {err.read()[-500:]}")
        return ChildResult(os.waitstatus_to_exitcode(doc["status"]), doc["wall_s"], doc["maxrss_kb"] / 1024.0,
                           out.read(), err.read(), doc["cpu_s"])


def _worker_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "autohaptics.bench.child", *args]


_CHILD_ENV: dict | None = None  # set by snapshot_source(): children import that copy of the package


def snapshot_source(dest: Path) -> Path:
    """Copy the ``autohaptics`` package to ``dest`` and make every measured child import that copy:
    a long run then measures one version of the code even when the working tree changes under it."""
    import compileall
    import shutil

    global _CHILD_ENV
    src = Path(__file__).resolve().parents[1]
    if dest.exists():
        shutil.rmtree(dest)
    shutil.copytree(src, dest / "autohaptics", ignore=shutil.ignore_patterns("*.pyc"))
    compileall.compile_dir(dest / "autohaptics", quiet=1)  # as installed: no child compiles its modules
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(dest)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    _CHILD_ENV = env
    return dest


def _child_json(cmd: list[str], result: Path) -> dict:
    r = run_child(cmd, env=_CHILD_ENV)
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or ["(no message)"])[-1]
        raise ParameterError(f"benchmark run failed (exit {r.returncode}): {' '.join(cmd[3:])}: {last}")
    doc = json.loads(result.read_text())
    doc["process_wall_s"] = r.wall_s
    doc["process_cpu_s"] = r.cpu_s
    doc["peak_rss_mb"] = r.peak_rss_mb
    return doc


def measure_decode(video: Path, work: Path) -> dict:
    """Bare decode of ``video`` (:func:`autohaptics.bench.decode.bare_decode`) in a fresh process:
    {"wall_s", "cpu_s", "peak_rss_mb", counts}."""
    res = work / "decode.result.json"
    return _child_json(_worker_cmd("_decode", str(video), str(res)), res)


def measure_generate(video: Path, config, work: Path) -> dict:
    """``generate`` of ``video`` with ``config`` in a fresh process; writes ``<name>.json`` (the timeline)."""
    res = work / f"{config.name}.result.json"
    tl = work / f"{config.name}.json"
    return _child_json(_worker_cmd("_generate", str(video), str(tl), str(res), *config.cli_args()), res)


# ------------------------------------------------------------------ workers (in the child)
def _worker_decode(argv: list[str]) -> None:
    from autohaptics.bench.decode import bare_decode

    video, result = argv
    cpu0, t0 = time.process_time(), time.perf_counter()
    counts = bare_decode(video)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    Path(result).write_text(json.dumps({"wall_s": wall, "cpu_s": cpu, **counts}))


def _worker_generate(argv: list[str]) -> None:
    import numpy as np

    from autohaptics.intensity import features as af
    from autohaptics.params import add_generation_options, params_from_args
    from autohaptics.pipeline import generate

    p = argparse.ArgumentParser()
    p.add_argument("video")
    p.add_argument("timeline")
    p.add_argument("result")
    add_generation_options(p)
    args = p.parse_args(argv)
    params, preset = params_from_args(args)
    # load the compiled audio kernels for this method (a one-off cost a long film pays once)
    af.compute_audio_features([np.zeros(9600, np.float32)], params=params.audio)
    cpu0, t0 = time.process_time(), time.perf_counter()
    tl = generate(args.video, params, preset=preset)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    tl.save(args.timeline)
    Path(args.result).write_text(json.dumps({"wall_s": wall, "cpu_s": cpu, "stats": tl.stats,
                                             "n_ticks": tl.n_ticks, "duration_s": tl.source.get("duration_s")}))




def _main(argv: list[str]) -> int:
    """Entry point of the measured child processes (``python -m autohaptics.bench.child``). A
    ``_generate`` child ends as the ``autohaptics generate`` program does
    (:func:`autohaptics.cli.main.end_process`); the bare decode as any script does."""
    if not argv or argv[0] not in ("_decode", "_generate"):
        print("usage: python -m autohaptics.bench.child _decode|_generate ... (use `autohaptics bench accuracy`)",
              file=sys.stderr)
        return 2
    if argv[0] == "_decode":
        _worker_decode(argv[1:])
        return 0
    from autohaptics.cli.main import end_process

    _worker_generate(argv[1:])
    end_process(0)


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
