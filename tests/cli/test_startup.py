"""Start-up: ``autohaptics --help`` and argument errors load none of the heavy libraries (checked by
what a fresh interpreter has imported, never by timing; the figures are in docs/BENCHMARKS.md)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from shared_data import REPO

HEAVY = ("numpy", "av", "cv2", "scipy", "numba", "autohaptics.pipeline", "autohaptics.params")
_PROBE = """
import json, sys
from autohaptics.cli.main import main
try:
    rc = main(sys.argv[1:])
except SystemExit as exc:
    rc = exc.code
print(json.dumps({"rc": rc, "modules": sorted(sys.modules)}), file=sys.stderr)
"""


def _run(*argv: str) -> tuple[int, list[str], str]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "backend"), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-c", _PROBE, *argv], capture_output=True, text=True, env=env, timeout=120)
    doc = json.loads(proc.stderr.strip().splitlines()[-1])
    return doc["rc"], doc["modules"], proc.stdout + proc.stderr


def test_help_imports_nothing_heavy():
    rc, modules, out = _run("--help")
    assert rc == 0
    for name in ("generate", "serve", "export", "import", "batch", "features", "compare", "chair", "bench"):
        assert f"    {name}" in out
    assert [m for m in HEAVY if m in modules] == []


@pytest.mark.parametrize("argv", [["no-such-command"], []])
def test_command_errors_import_nothing_heavy(argv):
    rc, modules, out = _run(*argv)
    assert rc == 2 and "usage: autohaptics" in out
    assert [m for m in HEAVY if m in modules] == []


def test_a_missing_argument_does_not_import_the_pipeline():
    # the command's options come from the parameter records (numpy); no pipeline, no compiler, no scipy
    rc, modules, out = _run("generate")
    assert rc == 2 and "the following arguments are required: video, -o/--output" in out
    assert [m for m in ("autohaptics.pipeline", "scipy", "numba", "onnxruntime") if m in modules] == []


@pytest.mark.parametrize("command", ["generate", "serve", "export", "import", "batch", "features", "compare",
                                     "chair", "bench"])
def test_every_command_has_its_own_help(command):
    rc, _, out = _run(command, "--help")
    assert rc == 0 and f"usage: autohaptics {command}" in out


def test_generate_imports_only_what_it_uses(tmp_path):
    """A plain ``generate`` (audio child included) loads no multiprocessing machinery, no socket
    module, no ``ctypes.util`` (whose library search runs ``ldconfig`` in a child process) and no
    ``numpy.ma`` (11 ms: numpy's median and percentile load it; :mod:`autohaptics.quantiles`)."""
    from shared_data import shared_clip

    out = tmp_path / "t.json"
    rc, modules, text = _run("generate", str(shared_clip("bbb_1s_1280x720_vp8_vorbis.webm")), "-o", str(out), "--quiet")
    assert rc == 0, text
    assert out.is_file()
    assert [m for m in ("multiprocessing", "multiprocessing.connection", "socket", "ctypes.util", "numpy.ma")
            if m in modules] == []


def test_end_process_runs_the_exit_handlers_and_flushes_the_streams():
    code = ("import atexit, sys\nfrom autohaptics.cli.main import end_process\n"
            "atexit.register(lambda: print('handler ran'))\nprint('written', end=' ')\nsys.stderr.write('err')\n"
            "end_process(3)\nprint('never')\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "backend"), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert (proc.returncode, proc.stdout, proc.stderr) == (3, "written handler ran\n", "err")


def test_the_generate_program_writes_its_timeline_and_summary_before_it_ends(tmp_path):
    from shared_data import shared_clip

    out = tmp_path / "t.json"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "backend"), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-m", "autohaptics.cli.main", "generate",
                           str(shared_clip("bbb_1s_1280x720_vp8_vorbis.webm")), "-o", str(out), "--quiet"],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.strip().splitlines()[-1].startswith(f"{out}: 10 ticks")
    assert json.loads(out.read_text())["n_ticks"] == 10
