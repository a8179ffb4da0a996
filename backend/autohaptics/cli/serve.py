"""``autohaptics serve``: the editor and its HTTP API on http://127.0.0.1:8000 (uvicorn)."""

from __future__ import annotations

import errno
import json
import sys
import threading
import time
from pathlib import Path

from autohaptics.errors import ParameterError

COMMAND = "serve"
HELP = "run the web editor and its HTTP API"


def register(sub) -> None:
    p = sub.add_parser(COMMAND, help=HELP,
                       description="Serve the editor (frontend/) and the API (docs/API.md); OpenAPI at /docs.")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to bind (default 127.0.0.1: the editor has no authentication)")
    p.add_argument("--port", type=int, default=8000, help="TCP port (default 8000)")
    p.add_argument("--allow-host", action="append", default=None, metavar="NAME",
                   help="a further Host name the editor may be reached by, e.g. a LAN name (repeatable; "
                        "default: only 127.0.0.1, localhost and the --host name; docs/API.md 'Security')")
    p.add_argument("--data", type=Path, default=None,
                   help="data folder for projects and the database (default $AUTOHAPTICS_DATA or ./data)")
    p.add_argument("--jobs", type=int, default=None, help="generation jobs running at once (default 1)")
    p.add_argument("--max-upload-mb", type=float, default=None, help="largest accepted upload in MiB (default 4096)")
    p.add_argument("--frontend", type=Path, default=None, help="static frontend folder (default: the repository's)")
    p.add_argument("--open-sample", action="store_true",
                   help="once the server is up, add the 10 s generated sample clip as a project and open the "
                        "editor on it in the browser")
    p.set_defaults(func=run)


def run(args) -> int:
    import uvicorn

    from autohaptics.server import folder_lock
    from autohaptics.server.app import create_app
    from autohaptics.server.settings import MIB, Settings

    if not 0 < args.port < 65536:
        raise ParameterError(f"--port must lie in 1..65535, got {args.port}")
    if args.jobs is not None and not 1 <= args.jobs <= 64:
        raise ParameterError(f"--jobs must lie in 1..64, got {args.jobs}")
    if args.max_upload_mb is not None and not 0 < args.max_upload_mb < 1e9:
        raise ParameterError(f"--max-upload-mb must be positive (MiB, below 1e9), got {args.max_upload_mb}")
    settings = Settings.from_env(
        data_dir=args.data, jobs=args.jobs, frontend_dir=args.frontend, bind_host=args.host,
        allowed_hosts=tuple(args.allow_host) if args.allow_host else None,
        max_upload_bytes=int(args.max_upload_mb * MIB) if args.max_upload_mb is not None else None)
    sock = bind_port(args.host, args.port)  # the port first: nothing printed or recovered on a busy one
    try:
        folder = folder_lock.acquire(settings.data_dir)
    except BaseException:
        sock.close()
        raise
    app = create_app(settings)
    url = f"http://{'127.0.0.1' if args.host in ('0.0.0.0', '::') else args.host}:{args.port}/"
    print(f"autohaptics: serving {url} (data in {folder}, API docs at {url}docs)", file=sys.stderr)
    if args.open_sample:
        threading.Thread(target=_open_sample, args=(url,), name="open-sample", daemon=True).start()
    # Open progress streams would hold a graceful stop until their jobs end: give them 5 s, then the
    # running jobs are recorded as interrupted (re-runnable).
    config = uvicorn.Config(app, log_level="info", timeout_graceful_shutdown=5)
    try:
        uvicorn.Server(config).run(sockets=[sock])
    except KeyboardInterrupt:  # uvicorn re-raises the Ctrl+C it has already handled
        pass
    finally:
        folder_lock.release(folder)
    return 0


def bind_port(host: str, port: int) -> socket.socket:
    """A socket bound to ``host:port``; ParameterError in one line when the port is taken."""
    import socket  # here, not at the top: every other command imports this module for its name

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except socket.gaierror as exc:
        raise ParameterError(f"--host {host}: {exc.strerror}") from None
    family, kind, proto, _, address = infos[0]
    sock = socket.socket(family, kind, proto)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(address)
        sock.listen(2048)
    except OSError as exc:
        sock.close()
        if exc.errno == errno.EADDRINUSE:
            raise ParameterError(f"port {port} on {host} is in use (another server?); choose another with --port") \
                from None
        raise ParameterError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    return sock


SAMPLE_NAME = "sample (10 s demo)"


def _open_sample(url: str) -> None:
    """Open the editor on the sample project: reuse it when the data folder has it, otherwise write
    the sample clip and upload it through the API once /health answers."""
    import urllib.error
    import urllib.request
    import uuid
    import tempfile
    import webbrowser

    try:
        from autohaptics.testing import sample_clip
    except ImportError as exc:
        print(f"autohaptics: no sample clip generator ({exc}); open {url} and upload a film", file=sys.stderr)
        return

    with tempfile.TemporaryDirectory(prefix="autohaptics-sample-") as tmp:
        clip = sample_clip(Path(tmp) / "sample.mp4")
        deadline = time.monotonic() + 60
        while True:
            try:
                with urllib.request.urlopen(f"{url}health", timeout=2):
                    break
            except (urllib.error.URLError, OSError):
                if time.monotonic() > deadline:
                    print(f"autohaptics: the server did not answer at {url}; sample not added", file=sys.stderr)
                    return
                time.sleep(0.25)
        with urllib.request.urlopen(f"{url}api/projects", timeout=10) as resp:
            existing = [p for p in json.load(resp) if p.get("name") == SAMPLE_NAME]
        if existing:
            webbrowser.open(f"{url}#/project/{existing[0]['id']}")
            return
        boundary = uuid.uuid4().hex
        body = b"".join([
            f"--{boundary}\r\nContent-Disposition: form-data; name=\"name\"\r\n\r\n{SAMPLE_NAME}\r\n".encode(),
            f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"sample.mp4\"\r\n"
            "Content-Type: video/mp4\r\n\r\n".encode(),
            clip.read_bytes(), f"\r\n--{boundary}--\r\n".encode()])
        req = urllib.request.Request(f"{url}api/projects", data=body, method="POST",
                                     headers={"Content-Type": f"multipart/form-data; boundary={boundary}"})
        try:
            with urllib.request.urlopen(req, timeout=60) as resp:
                project = json.load(resp)
        except urllib.error.HTTPError as exc:
            print(f"autohaptics: adding the sample failed: {exc.read().decode(errors='replace')}", file=sys.stderr)
            return
    webbrowser.open(f"{url}#/project/{project['id']}")
