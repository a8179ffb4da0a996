"""The editor's static files: HTML, scripts and styles revalidated on every load (and kept in
memory: a cold open asks for sixty of them at once), and the page
naming every module of ``src/`` up front (``<link rel="modulepreload">``), so a cold open fetches
them all at once instead of discovering them one import level after another (seven levels deep).
The links are added by a script at the page's ``<!-- modulepreload -->`` mark (else before
``</head>``): links in the markup are requested by Chromium's preload scanner before any inline
script runs, and the early data requests above the mark waited for all the modules.
"""

from __future__ import annotations

import json
import os
from mimetypes import guess_type
from pathlib import Path

from starlette.responses import Response
from starlette.staticfiles import StaticFiles

NO_CACHE_SUFFIXES = (".html", ".js", ".mjs", ".css", ".json")
MODULES_DIR = "src"
_MARKS = (b"<!-- modulepreload", b"</head>")


class FrontendFiles(StaticFiles):
    """Static files of the frontend folder; ``index.html`` gets the module preload links."""

    def __init__(self, *, directory: str | os.PathLike, html: bool = True):
        super().__init__(directory=directory, html=html)
        self._root = Path(directory)
        self._page: tuple[tuple, bytes] | None = None
        self._texts: dict[str, tuple[tuple, bytes]] = {}

    def file_response(self, full_path, stat_result, scope, status_code=200):
        if Path(full_path).name == "index.html" and Path(full_path).parent == self._root:
            return Response(self.page(Path(full_path)), status_code=status_code, media_type="text/html",
                            headers={"Cache-Control": "no-cache"})
        if not str(full_path).endswith(NO_CACHE_SUFFIXES):
            return super().file_response(full_path, stat_result, scope, status_code)
        key = (str(full_path), stat_result.st_mtime_ns, stat_result.st_size)
        body = self._texts.get(key[0])
        if body is None or body[0] != key:  # kept in memory: no file opened and read per request
            body = self._texts[key[0]] = (key, Path(full_path).read_bytes())
        media_type = guess_type(str(full_path))[0] or "text/plain"
        if media_type == "text/javascript":
            media_type = "application/javascript"
        return Response(body[1], status_code=status_code, media_type=media_type, headers={"Cache-Control": "no-cache"})

    def page(self, path: Path) -> bytes:
        """``index.html`` with a script adding a preload link for every module under ``src/`` at
        its mark, kept while the page and the module files are the same."""
        modules = sorted(p for p in (self._root / MODULES_DIR).rglob("*.js") if p.is_file())
        key = (path.stat().st_mtime_ns, tuple((str(p), p.stat().st_mtime_ns) for p in modules))
        if self._page is not None and self._page[0] == key:
            return self._page[1]
        text = path.read_bytes()
        names = json.dumps([p.relative_to(self._root).as_posix() for p in modules]).replace("</", "<\\/")
        links = (f'<script>{names}.forEach(function (href) {{ var link = document.createElement("link"); '
                 f'link.rel = "modulepreload"; link.href = href; document.head.appendChild(link); }});</script>\n  ').encode()
        at = next((i for i in (text.find(mark) for mark in _MARKS) if i >= 0), -1)
        page = text if at < 0 else text[:at] + links + text[at:]
        self._page = (key, page)
        return page
