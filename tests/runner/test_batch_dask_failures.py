"""``autohaptics batch --scheduler`` when the cluster fails, against a real ``dask scheduler`` and
``dask worker`` (separate processes, killed with SIGKILL): every case ends with one line and exit
status 2 within the documented bound (batch/cluster.py), never a hang or a traceback.

The bounds are shortened here (``NO_WORKERS_S``, ``LOST_SCHEDULER_S``) so the tests wait seconds;
the time limits asserted are hang checks with wide slack, not speed measurements.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from autohaptics.batch import cluster
from autohaptics.cli.main import main

from shared_data import shared_clip

CLIP = "bbb_opening_30s_1280x720_vp8_vorbis.webm"  # long enough to be running when its worker dies
DASK = str(Path(sys.executable).with_name("dask"))
HANG_S = 60.0  # beyond the shortened bound plus this, the batch counts as hung


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _start(args: list[str], log: Path) -> subprocess.Popen:
    with open(log, "w") as fh:
        return subprocess.Popen([DASK, *args], stdout=fh, stderr=subprocess.STDOUT, start_new_session=True)


def _kill(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(10)


@pytest.fixture
def cluster_procs(tmp_path):
    """A scheduler and one worker (no nanny: killing it leaves the cluster without workers)."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    scheduler = _start(["scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                       tmp_path / "scheduler.log")
    worker = None
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert scheduler.poll() is None and time.monotonic() < deadline, (tmp_path / "scheduler.log").read_text()
                time.sleep(0.2)
        worker = _start(["worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard"], tmp_path / "worker.log")
        yield address, scheduler, worker
    finally:
        for proc in (worker, scheduler):
            if proc is not None:
                _kill(proc)


def _kill_when_running(address: str, victim: subprocess.Popen, done: list) -> threading.Thread:
    """Kill ``victim`` once a task of the batch is running on the cluster; record when."""
    def watch():
        from distributed import Client

        with Client(address, timeout="30s", set_as_default=False) as client:
            deadline = time.monotonic() + 120
            while not any(client.processing().values()) and time.monotonic() < deadline:
                time.sleep(0.2)
        os.killpg(victim.pid, signal.SIGKILL)
        done.append(time.monotonic())

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    return thread


def _one_line(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("victim, bound, message", [
    ("worker", "NO_WORKERS_S", "has had no worker for 5 s"),
    ("scheduler", "LOST_SCHEDULER_S", "lost the Dask scheduler"),
])
def test_a_cluster_that_dies_ends_the_batch_with_one_line(cluster_procs, tmp_path, capsys, monkeypatch,
                                                          victim, bound, message):
    address, scheduler, worker = cluster_procs
    monkeypatch.setattr(cluster, bound, 5.0)
    killed: list[float] = []
    watcher = _kill_when_running(address, worker if victim == "worker" else scheduler, killed)
    rc = main(["batch", str(shared_clip(CLIP)), "-o", str(tmp_path / "out"), "--scheduler", address, "--quiet"])
    ended = time.monotonic()
    watcher.join(5)
    assert killed, "the batch ended before its task ran on the cluster"
    assert rc == 2
    line = _one_line(capsys.readouterr().err)
    assert message in line and address in line and "1 film(s) not done" in line, line
    assert ended - killed[0] < 5.0 + HANG_S
    assert not list((tmp_path / "out").glob("*.timeline.json"))


@pytest.mark.parametrize("address, message", [
    ("tcp://127.0.0.1:{free}", "no Dask scheduler answers there"),
    ("tcp://nonexistent.invalid:8786", "unknown host 'nonexistent.invalid'"),
    ("tcp://127.0.0.1:notaport", "expected tcp://HOST:PORT with a port in 1..65535"),
])
def test_a_bad_scheduler_address_fails_at_once(tmp_path, capsys, address, message):
    address = address.format(free=_free_port())
    started = time.monotonic()
    rc = main(["batch", str(shared_clip(CLIP)), "-o", str(tmp_path / "out"), "--scheduler", address, "--quiet"])
    assert rc == 2
    line = _one_line(capsys.readouterr().err)
    assert message in line and address in line, line
    assert time.monotonic() - started < cluster.CONNECT_S  # Dask's own retries would take 20 s and more
    assert not (tmp_path / "out").exists()
