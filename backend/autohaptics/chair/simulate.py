"""The virtual chair: the firmware's portable core compiled for this machine, on a pseudo-terminal.

:func:`build_simulator` compiles ``firmware/src/*.c`` + ``firmware/host/sim_main.c`` with the C
compiler on PATH (``$CC`` or ``cc``) into a cache directory outside the package source
(``$XDG_CACHE_HOME/autohaptics/chair`` or ``~/.cache/autohaptics/chair``, or ``build_dir``),
once per source version. :class:`VirtualChair` runs it: it opens a pty, keeps a stable symlink
(``link_path``) pointing at it so a restarted chair appears under the same device path, and
writes a JSON-lines log of every applied frame and state change (``t_ms`` = CLOCK_MONOTONIC
milliseconds, the same clock as :func:`time.monotonic`).

Virtual chairs started with the default link live in :func:`runtime_dir`, where
:func:`autohaptics.chair.ports.list_ports` finds them.
"""

from __future__ import annotations

import hashlib
import json
import os
import selectors
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from autohaptics.errors import DeviceError

FIRMWARE_ENV = "AUTOHAPTICS_FIRMWARE_DIR"
CORE_SOURCES = ("src/proto_wire.c", "src/proto_parser.c", "src/chair_core.c")
SIM_SOURCE = "host/sim_main.c"
CFLAGS = ("-std=c99", "-O2", "-Wall", "-Wextra", '-DAH_DEVICE_NAME="virtual-chair"')
BINARY_NAME = "autohaptics-chair-sim"
LINK_PREFIX = "virtual-chair-"


def firmware_dir() -> Path:
    """The firmware source tree: ``$AUTOHAPTICS_FIRMWARE_DIR`` or ``firmware/`` of this checkout."""
    env = os.environ.get(FIRMWARE_ENV)
    path = Path(env) if env else Path(__file__).resolve().parents[3] / "firmware"
    if not (path / SIM_SOURCE).is_file():
        raise DeviceError(f"firmware sources not found at {path} (need {SIM_SOURCE}); set {FIRMWARE_ENV} to the "
                          "repository's firmware/ directory")
    return path


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "autohaptics" / "chair"


def runtime_dir() -> Path:
    """Where virtual chairs keep their device links: ``$XDG_RUNTIME_DIR/autohaptics`` or
    ``/tmp/autohaptics-<uid>``."""
    base = os.environ.get("XDG_RUNTIME_DIR")
    path = Path(base) / "autohaptics" if base else Path(tempfile.gettempdir()) / f"autohaptics-{os.getuid()}"
    path.mkdir(parents=True, exist_ok=True, mode=0o700)
    return path


def default_link(name: str = "chair0") -> Path:
    return runtime_dir() / f"{LINK_PREFIX}{name}"


def _compiler(cc: str | None) -> str:
    cc = cc or os.environ.get("CC") or "cc"
    found = shutil.which(cc)
    if not found:
        raise DeviceError(f"no C compiler '{cc}' on PATH to build the virtual chair; install one "
                          "(Debian: apt-get install gcc) or set CC")
    return found


def build_simulator(*, build_dir: str | os.PathLike | None = None, cc: str | None = None,
                    force: bool = False) -> Path:
    """Compile the virtual chair if this source version is not built yet; return the binary's path."""
    src = firmware_dir()
    compiler = _compiler(cc)
    files = [src / f for f in CORE_SOURCES] + [src / SIM_SOURCE] + sorted((src / "src").glob("*.h"))
    digest = hashlib.sha256()
    for f in files:
        digest.update(f.name.encode() + b"\0" + f.read_bytes())
    digest.update(compiler.encode() + b"\0" + " ".join(CFLAGS).encode())
    out_dir = Path(build_dir) if build_dir else cache_dir()
    out_dir.mkdir(parents=True, exist_ok=True)
    binary = out_dir / f"{BINARY_NAME}-{digest.hexdigest()[:12]}"
    if binary.exists() and not force:
        return binary
    tmp = out_dir / f".{binary.name}.{os.getpid()}.tmp"
    cmd = [compiler, *CFLAGS, "-I", str(src / "src"), *(str(src / f) for f in CORE_SOURCES), str(src / SIM_SOURCE),
           "-o", str(tmp)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        tmp.unlink(missing_ok=True)
        raise DeviceError(f"building the virtual chair failed ({' '.join(cmd)}):\n{proc.stderr.strip()}")
    os.replace(tmp, binary)  # atomic: concurrent builds of the same version are harmless
    return binary


def read_log(path: str | os.PathLike) -> list[dict]:
    """Entries of a virtual chair log (complete lines only)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        return []
    entries = []
    for line in text.splitlines(keepends=True):
        if line.endswith("\n") and line.strip():
            entries.append(json.loads(line))
    return entries


class VirtualChair:
    """A running virtual chair. Use as a context manager or call :meth:`start` / :meth:`stop`.

    device    : the path to open (the stable link), also after :meth:`restart`
    pty       : the current pseudo-terminal slave (/dev/pts/N)
    log_path  : its JSON-lines log, or None
    """

    def __init__(self, *, link_path: str | os.PathLike | None = None, log_path: str | os.PathLike | None = None,
                 name: str = "chair0", binary: str | os.PathLike | None = None,
                 build_dir: str | os.PathLike | None = None, start_timeout_s: float = 5.0):
        self.link_path = Path(link_path) if link_path else default_link(name)
        self.log_path = Path(log_path) if log_path else None
        self._binary = Path(binary) if binary else None
        self._build_dir = build_dir
        self._start_timeout_s = start_timeout_s
        self._proc: subprocess.Popen | None = None
        self.pty: str | None = None

    @property
    def device(self) -> str:
        return str(self.link_path)

    @property
    def pid(self) -> int | None:
        return self._proc.pid if self._proc else None

    @property
    def alive(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def start(self) -> "VirtualChair":
        if self.alive:
            return self
        binary = self._binary or build_simulator(build_dir=self._build_dir)
        self.link_path.parent.mkdir(parents=True, exist_ok=True)
        cmd = [str(binary), "--link", str(self.link_path)]
        if self.log_path is not None:
            cmd += ["--log", str(self.log_path)]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
        line = _read_line(proc, self._start_timeout_s)
        if not line.startswith("/"):
            proc.kill()
            _, err = proc.communicate()
            raise DeviceError(f"virtual chair did not start ({' '.join(cmd)}): {err.decode(errors='replace').strip()}")
        self._proc = proc
        self.pty = line
        return self

    def stop(self, timeout_s: float = 3.0) -> None:
        """Terminate cleanly (the chair logs "exit" and removes its link)."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        _close_pipes(proc)

    def kill(self) -> None:
        """SIGKILL, as a crash or an unplug would: no exit line, the link is left dangling."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        _close_pipes(proc)

    def restart(self) -> "VirtualChair":
        self.stop()
        return self.start()

    def read_log(self) -> list[dict]:
        if self.log_path is None:
            raise DeviceError("this virtual chair was started without a log file")
        return read_log(self.log_path)

    def frames(self) -> list[dict]:
        """The applied-frame entries of the log, in order."""
        return [e for e in self.read_log() if e.get("ev") == "frame"]

    def wait_for(self, predicate: Callable[[dict], bool], timeout_s: float = 3.0, *, count: int = 1) -> dict:
        """Poll the log until ``count`` entries satisfy ``predicate``; return the count-th one."""
        deadline = time.monotonic() + timeout_s
        while True:
            matches = [entry for entry in self.read_log() if predicate(entry)]
            if len(matches) >= count:
                return matches[count - 1]
            if time.monotonic() > deadline:
                raise DeviceError(f"virtual chair log {self.log_path} has {len(matches)} of {count} matching "
                                  f"entries after {timeout_s} s")
            time.sleep(0.01)

    def __enter__(self) -> "VirtualChair":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
        if self.link_path.is_symlink() and not self.link_path.exists():
            self.link_path.unlink(missing_ok=True)  # left dangling by kill()

    def __repr__(self) -> str:
        return f"VirtualChair(device={self.device!r}, pty={self.pty!r}, pid={self.pid}, log={self.log_path})"


def virtual_chair_links() -> list[Path]:
    """Links of running virtual chairs in :func:`runtime_dir` (dangling ones skipped)."""
    out = []
    for p in sorted(runtime_dir().glob(f"{LINK_PREFIX}*")):
        if p.is_symlink() and p.exists() and not p.name.endswith(".tmp"):
            out.append(p)
    return out


def _read_line(proc: subprocess.Popen, timeout_s: float) -> str:
    assert proc.stdout is not None
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    buf = b""
    deadline = time.monotonic() + timeout_s
    try:
        while b"\n" not in buf:
            left = deadline - time.monotonic()
            if left <= 0 or not sel.select(left):
                break
            chunk = os.read(proc.stdout.fileno(), 4096)
            if not chunk:
                break
            buf += chunk
    finally:
        sel.close()
    return buf.split(b"\n", 1)[0].decode(errors="replace").strip()


def _close_pipes(proc: subprocess.Popen) -> None:
    for stream in (proc.stdout, proc.stderr):
        if stream is not None:
            stream.close()
