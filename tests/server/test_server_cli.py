"""``autohaptics serve``: argument checks, the Host names it answers to (``--host``, ``--allow-host``,
AUTOHAPTICS_ALLOW_HOSTS), and a real uvicorn server on 127.0.0.1 that stops cleanly."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
import wave
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from autohaptics.cli.main import main
from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings

from service_client import LocalClient
from shared_data import REPO
from test_server_jobs import sse, upload, wait_running



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


def _serve(*argv: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """``autohaptics serve ARGV`` as its own process, expected to exit by itself."""
    exe = Path(sys.executable).with_name("autohaptics")
    return subprocess.run([str(exe), "serve", *argv], capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, "PYTHONUNBUFFERED": "1"})


def test_serve_data_that_is_a_file_is_one_line(tmp_path):
    data = tmp_path / "data.txt"
    data.write_text("not a folder")
    done = _serve("--port", str(_free_port()), "--data", str(data))
    assert done.returncode == 2, done.stderr
    assert done.stderr == f"autohaptics: error: data folder {data} is not a folder\n", done.stderr
    assert data.read_text() == "not a folder"


def test_a_busy_port_is_one_line_before_anything_is_printed_or_touched(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        done = _serve("--port", str(port), "--data", str(tmp_path / "data"))
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert f"port {port}" in done.stderr and "serving" not in done.stderr + done.stdout
    assert not (tmp_path / "data").exists()


@pytest.mark.slow
def test_a_second_server_on_the_folder_exits_and_the_running_job_completes_untouched(tmp_path):
    """Server 1 (this process) runs a job; server 2 (a real ``serve``) on the same folder exits with
    one line naming the folder and this PID, before its recovery: the job ends done with a timeline.
    The job analyses 15 minutes of noise, so it is still running when server 2 has given up."""
    data, long_wav = tmp_path / "data", tmp_path / "noise_15min.wav"
    rate = 8_000
    with wave.open(str(long_wav), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes((np.random.default_rng(1).standard_normal(900 * rate) * 3000).astype("<i2").tobytes())
    with LocalClient(create_app(Settings(data_dir=data, frontend_dir=None))) as client:
        project = upload(client, long_wav)
        job = project["job"]["id"]
        wait_running(client, job)
        work = sorted(p.name for p in (data / "work").iterdir())
        assert work
        done = _serve("--port", str(_free_port()), "--data", str(data))
        assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
        assert f"data folder {data} is in use" in done.stderr and f"PID {os.getpid()}" in done.stderr
        assert "serving" not in done.stderr
        assert client.get(f"/api/jobs/{job}").json()["status"] == "running"
        assert sorted(p.name for p in (data / "work").iterdir()) == work
        final = sse(client, job)[-1]
        assert final[0] == "done", final
        assert client.get(f"/api/projects/{project['id']}").json()["has_timeline"]
        assert client.get(f"/api/projects/{project['id']}/timeline").status_code == 200


@pytest.mark.parametrize("argv, env, accepted, refused", [
    ([], None, ["127.0.0.1", "localhost"], ["studio.lan", "evil.example"]),
    (["--allow-host", "studio.lan", "--allow-host", "Booth.lan"], None, ["studio.lan", "booth.lan"], ["evil.example"]),
    ([], "studio.lan, booth.lan", ["studio.lan", "booth.lan", "localhost"], ["evil.example", "lan"]),
    (["--allow-host", "studio.lan"], "booth.lan", ["studio.lan"], ["booth.lan"]),  # the option wins
    (["--host", "studio.lan"], None, ["studio.lan", "127.0.0.1"], ["booth.lan", "evil.example"]),
])
def test_serve_answers_to_the_names_given_and_refuses_others(tmp_path, monkeypatch, capsys, argv, env,
                                                             accepted, refused):
    """``serve`` as run, up to uvicorn: the application it would serve is driven under each Host.
    ``--host NAME`` binds NAME; here the bind goes to 127.0.0.1 (NAME needs no DNS entry)."""
    import uvicorn

    from autohaptics.cli import serve

    if env is None:
        monkeypatch.delenv("AUTOHAPTICS_ALLOW_HOSTS", raising=False)
    else:
        monkeypatch.setenv("AUTOHAPTICS_ALLOW_HOSTS", env)
    bound: list[str] = []
    real_bind = serve.bind_port
    monkeypatch.setattr(serve, "bind_port", lambda host, port: bound.append(host) or real_bind("127.0.0.1", port))
    port, answers = _free_port(), {}

    def run(server, sockets=None):
        for sock in sockets:
            sock.close()
        with TestClient(server.config.app, base_url="http://127.0.0.1") as c:
            for name in accepted + refused:
                host = f"{name}:{port}"
                r = c.patch("/api/projects/nope", json={"name": "x"},
                            headers={"host": host, "origin": f"http://{host}"})
                answers[name] = (c.get("/api/projects", headers={"host": host}).status_code, r.status_code,
                                 r.json()["detail"])

    monkeypatch.setattr(uvicorn.Server, "run", run)
    assert main(["serve", "--port", str(port), "--data", str(tmp_path / "data"),
                 "--frontend", str(tmp_path / "none"), *argv]) == 0
    assert bound == [argv[1] if argv[:1] == ["--host"] else "127.0.0.1"]
    for name in accepted:
        assert answers[name][:2] == (200, 404), (name, answers[name])
    for name in refused:
        assert answers[name][:2] == (403, 403), (name, answers[name])
        assert answers[name][2] == (f"host {name!r} is not a name this service answers to; start it with "
                                    f"--allow-host {name} to allow it on purpose")
    if argv[:1] == ["--host"]:
        assert f"serving http://{argv[1]}:{port}/" in capsys.readouterr().err
