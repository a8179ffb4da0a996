"""``autohaptics serve``: argument checks, and a real uvicorn server on 127.0.0.1 that stops cleanly."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from autohaptics.cli.main import main
from shared_data import REPO



@pytest.mark.parametrize("argv, message", [
    (["serve", "--port", "0"], "--port must lie in 1..65535"),
    (["serve", "--jobs", "0"], "--jobs must lie in 1..64"),
    (["serve", "--max-upload-mb", "-1"], "--max-upload-mb must be positive"),
])
def test_bad_arguments_give_one_line_and_status_2(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_bad_environment_is_reported(monkeypatch, capsys):
    monkeypatch.setenv("AUTOHAPTICS_JOBS", "many")
    assert main(["serve", "--port", "8000"]) == 2
    assert "AUTOHAPTICS_JOBS" in capsys.readouterr().err


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (from /proc/*/stat)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _alive(pid: int) -> bool:
    try:
        return "\nState:\tZ" not in Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc to list the server's child processes")
def test_serve_runs_uvicorn_on_localhost_and_stops_cleanly(tmp_path):
    port = _free_port()
    frontend = tmp_path / "front"
    frontend.mkdir()
    (frontend / "index.html").write_text("<!doctype html><title>autohaptics editor</title>")
    exe = Path(sys.executable).with_name("autohaptics")
    cmd = [str(exe), "serve", "--port", str(port), "--data", str(tmp_path / "data"), "--frontend", str(frontend)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"}, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=2) as r:
                    assert json.load(r) == {"status": "ok", "version": "0.1.0"}
                break
            except OSError:
                assert proc.poll() is None, proc.stdout.read()
                assert time.monotonic() < deadline, "the server did not answer within 60 s"
                time.sleep(0.2)
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=5) as r:
            assert "autohaptics editor" in r.read().decode()
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/docs", timeout=5) as r:
            assert r.status == 200
        children = _children(proc.pid)
        assert children  # the Manager and the pool's worker
        os.killpg(proc.pid, signal.SIGINT)  # Ctrl+C in a terminal: the whole process group
        out, _ = proc.communicate(timeout=30)
        assert proc.returncode == 0, out
        assert f"serving http://127.0.0.1:{port}/" in out
        # The workers and the Manager are joined before the server exits; the resource tracker
        # (reparented) ends once its pipe closes.
        deadline = time.monotonic() + 20
        while any(_alive(c) for c in children) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not [c for c in children if _alive(c)]
        assert (tmp_path / "data" / "autohaptics.sqlite3").is_file()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
