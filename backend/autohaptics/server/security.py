"""The service's trust boundary: only its own pages (and local programs) may change anything.

Checked on every request before a route runs (docs/API.md "Security"):

- **Host**: the name must be one the service answers to (127.0.0.1, localhost, ::1, the ``--host``
  name, and ``Settings.allowed_hosts``); a DNS-rebinding page sends its own name and is refused.
- **Origin / Sec-Fetch-Site** on every method but GET and HEAD: a browser's request must come from
  the page's own origin (``Origin`` equal to ``http://`` + Host); a request without either header
  is a local program's. CORS preflights (OPTIONS) are refused: the service sends no CORS headers.
- **Token** on the chair routes and the event streams: a random per-folder token, given to the
  editor in an HttpOnly, SameSite=Strict cookie on its own GETs (or sent as ``X-Autohaptics-Token``).

A refusal is 403 with one sentence; nothing behind it runs.
"""

from __future__ import annotations

import hmac
import json
import os
import secrets
from collections.abc import Iterable
from pathlib import Path
from urllib.parse import urlsplit

LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")
WILDCARD_HOSTS = ("0.0.0.0", "::", "")
TOKEN_HEADER = "x-autohaptics-token"
TOKEN_FILE = "session.token"
COOKIE_PREFIX = "autohaptics_token_"
SAFE_METHODS = ("GET", "HEAD")
BROWSER_SAFE_SITES = ("same-origin", "none")


def host_names(bind_host: str | None, extra: Iterable[str] = ()) -> frozenset[str]:
    """The names the service answers to: the local ones, the bound name (unless a wildcard) and ``extra``."""
    names = {*LOCAL_HOSTS, *(h.strip().lower().rstrip(".") for h in extra if h.strip())}
    if bind_host is not None and bind_host.strip().lower() not in WILDCARD_HOSTS:
        names.add(bind_host.strip().lower().strip("[]").rstrip("."))
    return frozenset(names)


def folder_token(data_dir: Path) -> str:
    """The folder's token (created once, mode 0600): an open editor keeps working across restarts."""
    path = Path(data_dir) / TOKEN_FILE
    try:
        token = path.read_text().strip()
        if len(token) >= 32:
            return token
    except FileNotFoundError:
        pass
    token = secrets.token_urlsafe(32)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as fh:
        fh.write(token)
    return token


def split_host(host: str) -> tuple[str, str]:
    """("name", "port") of a Host header value; the name lower-cased, IPv6 brackets removed."""
    host = host.strip().lower()
    if host.startswith("["):
        name, _, rest = host[1:].partition("]")
        return name, rest.removeprefix(":")
    name, _, port = host.partition(":")
    return name.rstrip("."), port


class TrustBoundary:
    """ASGI middleware enforcing the checks of the module docstring; ``token`` is read per request
    from ``token_of(app)`` so the lifespan can create it in the data folder."""

    def __init__(self, app, *, names: frozenset[str], token_of):
        self.app = app
        self.names = names
        self.token_of = token_of

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}
        refusal = self.refusal(scope, headers)
        if refusal is not None:
            return await _refuse(send, refusal)
        cookie_name = COOKIE_PREFIX + (split_host(headers.get("host", ""))[1] or "80")
        token = self.token_of()
        has_token = _has_token(headers, cookie_name, token)
        if needs_token(scope["path"]) and not has_token:
            return await _refuse(send, "this request needs the session token: load the editor first, or send "
                                       "the X-Autohaptics-Token header (GET /api/session gives it)")
        browser_same_origin = headers.get("sec-fetch-site", "none") in BROWSER_SAFE_SITES
        if has_token or token is None or scope["method"] not in SAFE_METHODS or not browser_same_origin:
            return await self.app(scope, receive, send)
        cookie = f"{cookie_name}={token}; Path=/; HttpOnly; SameSite=Strict".encode("latin-1")

        async def send_with_cookie(message):
            if message["type"] == "http.response.start":
                message = {**message, "headers": [*message.get("headers", []), (b"set-cookie", cookie)]}
            await send(message)

        return await self.app(scope, receive, send_with_cookie)

    def refusal(self, scope, headers: dict[str, str]) -> str | None:
        """The one-sentence reason to refuse this request, or None."""
        host = headers.get("host")
        if not host:
            return "the request has no Host header"
        name, _ = split_host(host)
        if name not in self.names:
            return (f"host {name!r} is not a name this service answers to; start it with --allow-host {name} "
                    "to allow it on purpose")
        method = scope["method"]
        if method == "OPTIONS" and "access-control-request-method" in headers:
            return "cross-origin requests are refused"
        if method in SAFE_METHODS:
            return None
        origin = headers.get("origin")
        if origin is not None:
            parts = urlsplit(origin)
            if parts.scheme not in ("http", "https") or parts.netloc.lower() != host.strip().lower():
                return f"requests from another origin ({origin[:200]}) are refused"
            return None
        if headers.get("sec-fetch-site", "same-origin") not in BROWSER_SAFE_SITES:
            return "requests from another site are refused"
        return None


def needs_token(path: str) -> bool:
    """The chair routes and the event streams (Server-Sent Events) need the token."""
    return path.startswith("/api/chair/") or (path.startswith("/api/") and path.endswith("/events"))


def _has_token(headers: dict[str, str], cookie_name: str, token: str | None) -> bool:
    if token is None:
        return False
    given = headers.get(TOKEN_HEADER) or _cookie(headers.get("cookie", ""), cookie_name)
    return given is not None and hmac.compare_digest(given.encode("latin-1"), token.encode("latin-1"))


def _cookie(header: str, name: str) -> str | None:
    for part in header.split(";"):
        key, _, value = part.strip().partition("=")
        if key == name:
            return value
    return None


async def _refuse(send, message: str) -> None:
    body = json.dumps({"detail": message}).encode()
    await send({"type": "http.response.start", "status": 403,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})
