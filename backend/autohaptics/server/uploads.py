"""Receiving uploads: a streaming multipart reader with a size limit, and media acceptance.

:func:`receive_upload` writes the one file part of a ``multipart/form-data`` request straight to
a server-named file in chunks, counting bytes; past the limit it stops, removes the partial file
and raises :class:`UploadTooLarge` (413). The client's file name is returned only as text, for
display (:func:`display_name`), never used as a path.

:func:`inspect_media` decides whether an uploaded file is usable media: :func:`media.probe`
(not media, empty, no streams -> :class:`MediaRejected` 415) and a demux-only scan of the packet
times against the declared duration (cut or damaged -> 422), so a truncated film is refused at
upload rather than failing later in a job.
"""

from __future__ import annotations

import os
import re
import unicodedata
from collections.abc import AsyncIterator
from dataclasses import dataclass, field
from pathlib import Path

import anyio
from python_multipart.exceptions import FormParserError
from python_multipart.multipart import MultipartParser, parse_options_header

from autohaptics import media
from autohaptics.errors import AutohapticsError, MediaError, ParameterError

MAX_FIELD_BYTES = 64 * 1024
MAX_NAME_CHARS = 200
_WRITE_BLOCK = 1 << 20
_MULTIPART_OVERHEAD = 1 << 20  # room for the form fields and boundaries around the file


class UploadTooLarge(AutohapticsError):
    """The upload exceeds the configured limit (HTTP 413)."""


class MediaRejected(AutohapticsError):
    """An uploaded file is not usable media; ``status`` is 415 (not media) or 422 (damaged)."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


@dataclass
class Upload:
    path: Path  # where the file part was written
    filename: str  # the client's file name, as sent (display only)
    size: int
    fields: dict[str, str] = field(default_factory=dict)


# ------------------------------------------------------------------------ names
def display_name(raw: str | None, *, basename: bool = True, fallback: str = "untitled") -> str:
    """A safe display name: the last path component (``basename``), without control or format
    characters (NUL, newlines, bidi overrides), trimmed to 200 characters; ``fallback`` if empty."""
    text = raw or ""
    if basename:
        text = text.replace("\\", "/").rsplit("/", 1)[-1]
    text = "".join(ch for ch in text if unicodedata.category(ch)[0] not in ("C", "Z") or ch == " ")
    text = text.strip()[:MAX_NAME_CHARS].strip()
    if basename and text in ("", ".", ".."):
        return fallback
    return text or fallback


# ---------------------------------------------------------------------- receive
async def receive_upload(headers, stream: AsyncIterator[bytes], dest: Path, *, max_bytes: int,
                         file_field: str = "file") -> Upload:
    """Stream the ``file_field`` part of a multipart body to ``dest``; other parts are small text fields.

    headers : the request headers (Content-Type with the boundary, Content-Length when known).
    Raises UploadTooLarge past ``max_bytes`` of file data, ParameterError for a body that is not
    multipart, has no such file part or has a field over 64 KiB. ``dest`` is removed on any error.
    """
    ctype, options = parse_options_header(headers.get("content-type", ""))
    if ctype != b"multipart/form-data" or b"boundary" not in options:
        raise ParameterError("expected a multipart/form-data body with a file field "
                             f"{file_field!r} (Content-Type was {headers.get('content-type')!r})")
    length = headers.get("content-length")
    if length and length.isdigit() and int(length) > max_bytes + _MULTIPART_OVERHEAD:
        raise UploadTooLarge(f"the upload ({int(length)} bytes) exceeds the limit of {max_bytes} bytes")
    reader = _Reader(file_field, max_bytes)
    parser = MultipartParser(options[b"boundary"], reader.callbacks())
    try:
        with open(dest, "wb") as fh:
            reader.fh = fh
            async for chunk in stream:
                try:
                    parser.write(chunk)
                except FormParserError as exc:
                    raise ParameterError(f"malformed multipart body ({exc})") from None
                if reader.error is not None:
                    raise reader.error
                if len(reader.pending) >= _WRITE_BLOCK:
                    await reader.flush()
            try:
                parser.finalize()
            except FormParserError as exc:
                raise ParameterError(f"malformed multipart body ({exc})") from None
            if reader.error is not None:
                raise reader.error
            await reader.flush()
        if reader.filename is None:
            raise ParameterError(f"the form has no file field {file_field!r}")
    except BaseException:
        dest.unlink(missing_ok=True)
        raise
    return Upload(path=dest, filename=reader.filename, size=reader.size, fields=reader.fields)


class _Reader:
    """Callbacks of python-multipart's parser: file bytes are buffered for :meth:`flush`."""

    def __init__(self, file_field: str, max_bytes: int):
        self.file_field = file_field
        self.max_bytes = max_bytes
        self.fh = None
        self.pending = bytearray()
        self.size = 0
        self.filename: str | None = None
        self.fields: dict[str, str] = {}
        self.error: Exception | None = None
        self._header_name = b""
        self._header_value = b""
        self._disposition = b""
        self._part_name: str | None = None
        self._part_is_file = False
        self._field_data = bytearray()

    def callbacks(self) -> dict:
        return {"on_part_begin": self.on_part_begin, "on_part_data": self.on_part_data,
                "on_part_end": self.on_part_end, "on_header_field": self.on_header_field,
                "on_header_value": self.on_header_value, "on_header_end": self.on_header_end,
                "on_headers_finished": self.on_headers_finished}

    def on_part_begin(self) -> None:
        self._disposition = b""
        self._part_name = None
        self._part_is_file = False
        self._field_data = bytearray()

    def on_header_field(self, data: bytes, start: int, end: int) -> None:
        self._header_name += data[start:end]

    def on_header_value(self, data: bytes, start: int, end: int) -> None:
        self._header_value += data[start:end]

    def on_header_end(self) -> None:
        if self._header_name.lower() == b"content-disposition":
            self._disposition = self._header_value
        self._header_name = b""
        self._header_value = b""

    def on_headers_finished(self) -> None:
        _, opts = parse_options_header(self._disposition)
        name = opts.get(b"name")
        self._part_name = name.decode("utf-8", "replace") if name is not None else None
        if self._part_name == self.file_field and b"filename" in opts:
            if self.filename is not None:
                self.error = ParameterError(f"the form holds more than one {self.file_field!r} file")
                return
            self._part_is_file = True
            self.filename = opts[b"filename"].decode("utf-8", "replace")
        elif b"filename" in opts:
            self.error = ParameterError(f"the form sends a file in field {self._part_name!r}; "
                                        f"send it in field {self.file_field!r}")

    def on_part_data(self, data: bytes, start: int, end: int) -> None:
        if self.error is not None:
            return
        n = end - start
        if self._part_is_file:
            self.size += n
            if self.size > self.max_bytes:
                self.error = UploadTooLarge(f"the upload exceeds the limit of {self.max_bytes} bytes")
                return
            self.pending += data[start:end]
        elif self._part_name is not None:
            if len(self._field_data) + n > MAX_FIELD_BYTES:
                self.error = ParameterError(f"form field {self._part_name!r} is larger than {MAX_FIELD_BYTES} bytes")
                return
            self._field_data += data[start:end]

    def on_part_end(self) -> None:
        if not self._part_is_file and self._part_name is not None and self.error is None:
            self.fields[self._part_name] = self._field_data.decode("utf-8", "replace")

    async def flush(self) -> None:
        if self.pending:
            block, self.pending = bytes(self.pending), bytearray()
            await anyio.to_thread.run_sync(self.fh.write, block)


# ------------------------------------------------------------------------ media
@dataclass(frozen=True)
class Accepted:
    info: media.MediaInfo
    ext: str  # file name suffix chosen from the probed container, with the dot
    media_type: str  # what GET /media sends as Content-Type


def inspect_media(path: Path, *, name: str) -> Accepted:
    """Probe ``path`` and check it is complete; MediaRejected (415/422) naming ``name`` otherwise."""
    try:
        info = media.probe(path)
    except MediaError as exc:
        raise MediaRejected(415, _rename(str(exc), path, name)) from None
    try:
        check_complete(info)
    except MediaError as exc:
        raise MediaRejected(422, _rename(str(exc), path, name)) from None
    ext, media_type = container_suffix(info)
    return Accepted(info=info, ext=ext, media_type=media_type)


def check_complete(info: media.MediaInfo) -> None:
    """Raise MediaError when the packets of the file end clearly before its declared duration."""
    media.check_complete(info)


_WEBM_CODECS = {"vp8", "vp9", "av1", "vorbis", "opus"}
_SIMPLE = {"avi": (".avi", "video/x-msvideo"), "wav": (".wav", "audio/wav"), "mp3": (".mp3", "audio/mpeg"),
           "flac": (".flac", "audio/flac"), "ogg": (".ogg", "video/ogg"), "mpegts": (".ts", "video/mp2t"),
           "mpeg": (".mpg", "video/mpeg")}


def container_suffix(info: media.MediaInfo) -> tuple[str, str]:
    """(file suffix, Content-Type) for the probed container: the stored file's name never comes
    from the client."""
    names = info.container.split(",")
    codecs = {s.codec for s in (info.video, info.audio) if s is not None}
    has_video = info.video is not None
    if "matroska" in names or "webm" in names:
        if codecs <= _WEBM_CODECS:
            return ".webm", "video/webm" if has_video else "audio/webm"
        return ".mkv", "video/x-matroska" if has_video else "audio/x-matroska"
    if "mov" in names or "mp4" in names:
        return (".mp4", "video/mp4") if has_video else (".m4a", "audio/mp4")
    for n in names:
        if n in _SIMPLE:
            ext, mime = _SIMPLE[n]
            if n == "ogg" and not has_video:
                mime = "audio/ogg"
            return ext, mime
    stem = re.sub(r"[^a-z0-9]", "", names[0].lower())[:8] or "media"
    return f".{stem}", "application/octet-stream"


def _rename(message: str, path: Path, name: str) -> str:
    """Error messages name the file: show the client's name instead of the server's path."""
    return message.replace(str(path), name).replace(os.fspath(path.name), name)


def multipart_body(file_description: str, **fields: dict) -> dict:
    """The OpenAPI ``requestBody`` of a multipart upload route: a required ``file`` and the other
    form ``fields`` (name -> JSON schema), for the route's ``openapi_extra``."""
    properties = {"file": {"type": "string", "format": "binary", "description": file_description}, **fields}
    return {"requestBody": {"required": True, "content": {"multipart/form-data": {"schema": {
        "type": "object", "required": ["file"], "properties": properties}}}}}
