"""A private ``autohaptics serve`` in a child process, for the benchmarks and the browser tests."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx


class ServerError(RuntimeError):
    """``autohaptics serve`` did not come up; the message holds the end of its log."""


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(data: Path, *, log_path: Path, port: int | None = None, jobs: int = 1,
                 frontend: Path | None = None, timeout_s: float = 60.0,
                 cwd: Path | None = None) -> tuple[subprocess.Popen, str]:
    """Start ``autohaptics serve`` on ``port`` (a free one by default) with the data folder ``data``;
    returns (process, base URL) once /health answers. Its output is appended to ``log_path``."""
    port = port or free_port()
    log_path.parent.mkdir(parents=True, exist_ok=True)
    cmd = [sys.executable, "-m", "autohaptics.cli.main", "serve", "--host", "127.0.0.1", "--port", str(port),
           "--data", str(data), "--jobs", str(jobs)]
    if frontend is not None:
        cmd += ["--frontend", str(frontend)]
    with open(log_path, "a") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=cwd, start_new_session=True)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + timeout_s
    while True:
        if proc.poll() is not None:
            raise ServerError(f"autohaptics serve exited with {proc.returncode}:\n{log_path.read_text()[-3000:]}")
        try:
            if httpx.get(f"{url}/health", timeout=1.0).status_code == 200:
                return proc, url
        except httpx.HTTPError:
            pass
        if time.monotonic() > deadline:
            stop_server(proc)
            raise ServerError(f"autohaptics serve did not answer /health within {timeout_s} s:\n"
                              f"{log_path.read_text()[-3000:]}")
        time.sleep(0.2)


def stop_server(proc: subprocess.Popen, timeout_s: float = 15.0) -> None:
    """SIGTERM the server's process group (uvicorn and the job workers), SIGKILL if it lingers."""
    if proc.poll() is not None:
        return
    os.killpg(proc.pid, signal.SIGTERM)
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
