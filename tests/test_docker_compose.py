"""docker-compose.yml and the Dockerfile, checked without a Docker engine: ``docker-compose config``
(Debian's docker-compose v1, installed by ``scripts/setup --test``) validates and resolves the
file; the build context is computed with docker-py's own ``.dockerignore`` matcher, the one
docker-compose v1 builds with."""

from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from shared_data import REPO

COMPOSE_FILE = REPO / "docker-compose.yml"
DOCKERFILE = REPO / "Dockerfile"
SERVICE = "autohaptics"


def _compose() -> str:
    exe = shutil.which("docker-compose")
    if exe is None:
        pytest.skip("docker-compose is not installed: `scripts/setup --test` installs Debian's docker-compose "
                    "package (the v1 `docker-compose config` validates the file without a Docker engine)")
    return exe


def _config(compose_file: Path) -> dict:
    """``docker-compose config`` of ``compose_file`` (project directory: the repository), parsed."""
    run = subprocess.run([_compose(), "--project-directory", str(REPO), "-f", str(compose_file), "config"],
                         capture_output=True, text=True, timeout=120, cwd=REPO)
    assert run.returncode == 0, f"docker-compose config failed:\n{run.stderr}"
    return yaml.safe_load(run.stdout)


def _dockerfile_instructions() -> list[tuple[str, str]]:
    """(INSTRUCTION, arguments) of the Dockerfile, continuation lines joined, comments dropped."""
    text = re.sub(r"\\\n", " ", "\n".join(ln for ln in DOCKERFILE.read_text().splitlines()
                                          if not ln.lstrip().startswith("#")))
    out = []
    for line in text.splitlines():
        if line.strip():
            word, _, rest = line.strip().partition(" ")
            out.append((word.upper(), rest.strip()))
    return out


def test_compose_config_service_volume_localhost_port_healthcheck_build():
    cfg = _config(COMPOSE_FILE)
    assert list(cfg["services"]) == [SERVICE]
    svc = cfg["services"][SERVICE]

    assert Path(svc["build"]["context"]) == REPO
    assert (REPO / svc["build"].get("dockerfile", "Dockerfile")).resolve() == DOCKERFILE

    assert svc["ports"] == ["127.0.0.1:8000:8000/tcp"]  # never published beyond localhost

    assert svc["volumes"] == ["projects:/data:rw"]
    assert "projects" in cfg["volumes"] and not cfg["volumes"]["projects"].get("external")
    command = svc["command"]
    assert command[:2] == ["autohaptics", "serve"]
    assert command[command.index("--data") + 1] == "/data"  # the projects live in the named volume
    assert command[command.index("--host") + 1] == "0.0.0.0"
    assert command[command.index("--port") + 1] == "8000"

    check = svc["healthcheck"]
    assert check["test"][0] == "CMD" and "http://127.0.0.1:8000/health" in " ".join(check["test"])
    assert {"interval", "timeout", "retries"} <= set(check)


def test_the_commented_serial_device_entry_is_valid_when_uncommented(tmp_path):
    text = COMPOSE_FILE.read_text()
    assert "# devices:" in text and "/dev/ttyACM0:/dev/ttyACM0" in text and "# group_add:" in text
    enabled = re.sub(r"^(\s*)# (devices:|group_add:|  - /dev/ttyACM0:/dev/ttyACM0|  - dialout)$", r"\1\2", text,
                     flags=re.M)
    assert enabled != text
    copy = tmp_path / "docker-compose.yml"
    copy.write_text(enabled)
    svc = _config(copy)["services"][SERVICE]
    assert svc["devices"] == ["/dev/ttyACM0:/dev/ttyACM0"]
    assert svc["group_add"] == ["dialout"]
    assert "devices" not in _config(COMPOSE_FILE)["services"][SERVICE]  # off unless the user enables it


def test_dockerfile_installs_like_the_readme_and_serves_what_compose_runs():
    steps = _dockerfile_instructions()
    base = next(args for word, args in steps if word == "FROM")
    assert re.fullmatch(r"debian:(bookworm|trixie)(-slim)?", base), base  # Debian with Python >= 3.11
    runs = [args for word, args in steps if word == "RUN"]
    assert any(args.split("&&")[0].strip() == "scripts/setup" for args in runs), \
        "the image must install with scripts/setup, as the README does"
    apt = next(args for args in runs if "apt-get install" in args)
    assert {"gcc", "make", "libc6-dev"} <= set(apt.split()), "the virtual chair compiles firmware/ with gcc"
    env = " ".join(args for word, args in steps if word == "ENV")
    assert "PATH=/app/.venv/bin:" in env
    copied = {shlex.split(args)[0].rstrip("/") for word, args in steps if word == "COPY"}
    assert {"README.md", "scripts", "backend", "frontend", "firmware"} <= copied
    cmd = json.loads(next(args for word, args in steps if word == "CMD"))
    assert cmd == _config(COMPOSE_FILE)["services"][SERVICE]["command"]
    health = next(args for word, args in steps if word == "HEALTHCHECK")
    assert "http://127.0.0.1:8000/health" in health
    assert any(word == "USER" and args != "root" for word, args in steps)


def test_build_context_has_what_the_image_needs_and_no_local_environment():
    compose = _compose()
    python = Path(compose).read_text().splitlines()[0].removeprefix("#!").split()
    patterns = [ln.strip() for ln in (REPO / ".dockerignore").read_text().splitlines()
                if ln.strip() and not ln.lstrip().startswith("#")]
    script = ("import json, sys; from docker.utils.build import exclude_paths; "
              "print(json.dumps(sorted(exclude_paths(sys.argv[1], json.loads(sys.argv[2]), 'Dockerfile'))))")
    run = subprocess.run([*python, "-c", script, str(REPO), json.dumps(patterns)], capture_output=True, text=True,
                         timeout=120)
    if run.returncode != 0 and "No module named 'docker'" in run.stderr:
        pytest.skip("docker-py (a dependency of Debian's docker-compose) is not importable by docker-compose's Python")
    assert run.returncode == 0, run.stderr
    context = set(json.loads(run.stdout))

    from autohaptics.chair.simulate import CORE_SOURCES, SIM_SOURCE

    needed = {"README.md", "scripts/setup", "backend/pyproject.toml", "backend/autohaptics/__init__.py",
              "backend/autohaptics/cli/main.py", "frontend/index.html", "Dockerfile",
              *(f"firmware/{p}" for p in (*CORE_SOURCES, SIM_SOURCE))}
    assert needed <= context, sorted(needed - context)
    tracked = subprocess.run(["git", "ls-files", "frontend/src", "backend/autohaptics", "firmware/src"], cwd=REPO,
                             capture_output=True, text=True, check=True).stdout.split()
    tracked = {p for p in tracked if (REPO / p).is_file()}
    assert tracked <= context, sorted(tracked - context)[:10]
    for local in (".git/", ".venv/", "frontend/node_modules/", "out/", "data/", "test-artifacts/", "tests/"):
        assert not any(p.startswith(local) for p in context), local
    assert not any("__pycache__/" in p or p.endswith(".pyc") for p in context)
