"""``autohaptics chair ...`` sub-commands against the virtual chair. The chair module's own
``register()`` builds the parser, so these tests do not depend on other sub-commands."""

from __future__ import annotations

import argparse
import json
import re
import signal
import subprocess
import sys
import uuid
from pathlib import Path

import pytest

from autohaptics.chair import VirtualChair
from autohaptics.chair.simulate import read_log
from autohaptics.cli import chair as chair_cli
from autohaptics.errors import DeviceError
from autohaptics.timeline import Timeline


def run_cli(*argv: str) -> int:
    parser = argparse.ArgumentParser(prog="autohaptics")
    chair_cli.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(list(argv))
    return args.func(args)


def test_push_stop_and_status(chair, tmp_path, capsys):
    tl = Timeline.empty(6)
    tl.vibration[:, 4] = 0.5
    path = tl.save(tmp_path / "t.json")
    assert run_cli("chair", "push", str(path), "--port", chair.device, "--start", "0.2", "--intensity", "0.5",
                   "--mute", "seat") == 0
    out = capsys.readouterr().out
    sent, skipped = map(int, re.search(r"pushed (\d+) frames .* (\d+) skipped", out).groups())
    assert sent + skipped == 4  # 4 frames, 0 skipped, unless the host stalled
    chair.wait_for(lambda e: e["ev"] == "stop")  # everything before the final STOP is logged
    frames = chair.frames()
    assert len(frames) == sent and all(2 <= e["tick"] <= 5 for e in frames)
    assert all(e["motors"][4] == 64 for e in frames)  # floor(0.5 * 0.5 * 255 + 0.5)
    assert run_cli("chair", "stop", "--port", chair.device) == 0
    assert "chair state: safe" in capsys.readouterr().out
    assert run_cli("chair", "status", "--port", chair.device, "--json") == 0
    status = json.loads(capsys.readouterr().out)
    assert status["capabilities"]["name"] == "virtual-chair" and status["chair"]["frames_ok"] == 4
    assert status["chair"]["stopped"] is True
    assert run_cli("chair", "status", "--port", chair.device) == 0
    out = capsys.readouterr().out
    assert "9 actuators" in out and "frames_ok 4" in out and "safe (stop)" in out


def test_ports_lists_a_running_virtual_chair(sim_binary, capsys):
    with VirtualChair(name=f"cli-{uuid.uuid4().hex[:8]}", binary=sim_binary) as vc:
        assert run_cli("chair", "ports", "--json") == 0
        ports = json.loads(capsys.readouterr().out)
        assert {"device": vc.device, "kind": "virtual"}.items() <= next(p for p in ports if p["device"] == vc.device).items()
        assert run_cli("chair", "ports") == 0
        assert f"* {vc.device}" in capsys.readouterr().out


def test_errors_name_the_port(tmp_path):
    with pytest.raises(DeviceError, match="cannot open chair port"):
        run_cli("chair", "status", "--port", str(tmp_path / "nothing"))


def test_simulate_prints_the_device_and_stops_cleanly(tmp_path, sim_binary):
    link, log = tmp_path / "sim-link", tmp_path / "sim.jsonl"
    code = ("import argparse, sys; from autohaptics.cli import chair; p = argparse.ArgumentParser(); "
            "chair.register(p.add_subparsers()); a = p.parse_args(sys.argv[1:]); sys.exit(a.func(a))")
    proc = subprocess.Popen([sys.executable, "-c", code, "chair", "simulate", "--link", str(link), "--log", str(log),
                             "--build-dir", str(sim_binary.parent)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        device = proc.stdout.readline().strip()
        assert device == str(link) and Path(device).resolve().as_posix().startswith("/dev/pts/")
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(10) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.stdout.close()
        proc.stderr.close()
    assert not link.exists()
    assert [e["ev"] for e in read_log(log)] == ["start", "exit"]
