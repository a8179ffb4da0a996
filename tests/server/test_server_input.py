"""Bad input through the editor's API: every refusal is a clear 4xx and leaves the data folder as it was."""

from __future__ import annotations

import json
import re
import uuid
from pathlib import Path

import pytest

from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings

from shared_data import shared_clip
from service_client import LocalClient

CLIP = "bbb_1s_1280x720_vp8_vorbis.webm"  # 86 kB
LIMIT = 100_000


def files_of(data_dir: Path) -> dict[str, tuple[int, int]]:
    """Every file under the data folder except the database: {path: (size, mtime_ns)}."""
    return {str(p.relative_to(data_dir)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in sorted(data_dir.rglob("*")) if p.is_file() and not p.name.startswith("autohaptics.sqlite3")}


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("server-input")


@pytest.fixture(scope="module")
def client(root):
    settings = Settings(data_dir=root / "data", frontend_dir=None, max_upload_bytes=LIMIT)
    with LocalClient(create_app(settings)) as c:
        yield c


@pytest.fixture
def unchanged(client, root):
    """Asserts after the test that no file and no project appeared, changed or vanished."""
    data = root / "data"
    before = (files_of(data), client.get("/api/projects").json())
    yield
    assert (files_of(data), client.get("/api/projects").json()) == before
    assert list((data / "uploads").iterdir()) == []


def post_file(client, filename: str, content: bytes, **fields):
    return client.post("/api/projects", files={"file": (filename, content, "application/octet-stream")},
                       data={k: str(v) for k, v in fields.items()})


def test_non_media_upload_is_415(client, unchanged):
    r = post_file(client, "movie.mp4", b"this is a text file, not a film\n" * 100)
    assert r.status_code == 415
    assert r.json()["detail"].startswith("movie.mp4: not a readable media file")


def test_zero_byte_upload_is_415(client, unchanged):
    r = post_file(client, "empty.webm", b"")
    assert r.status_code == 415 and "empty (0 bytes)" in r.json()["detail"]


def test_truncated_video_is_422(client, unchanged):
    data = shared_clip(CLIP).read_bytes()
    r = post_file(client, "half.webm", data[: len(data) // 2])
    assert r.status_code == 422
    assert re.match(r"half\.webm: truncated or damaged file", r.json()["detail"]), r.json()


def test_oversize_upload_is_413_with_and_without_content_length(client, unchanged):
    r = post_file(client, "big.webm", b"\0" * (LIMIT + 2_000_000))
    assert r.status_code == 413 and "limit" in r.json()["detail"]
    # A chunked body (no Content-Length) is cut off while streaming, the partial file removed.
    boundary = uuid.uuid4().hex

    def body():
        yield (f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"big.webm\"\r\n"
               "Content-Type: video/webm\r\n\r\n").encode()
        for _ in range(40):
            yield b"\1" * 8192
        yield f"\r\n--{boundary}--\r\n".encode()

    r = client.post("/api/projects", content=body(),
                    headers={"Content-Type": f"multipart/form-data; boundary={boundary}"})
    assert r.status_code == 413 and f"limit of {LIMIT} bytes" in r.json()["detail"]


@pytest.mark.parametrize("body, headers, message", [
    (b'{"file": "x"}', {"Content-Type": "application/json"}, "expected a multipart/form-data body"),
    (b"--b\r\nContent-Disposition: form-data; name=\"name\"\r\n\r\nx\r\n--b--\r\n",
     {"Content-Type": "multipart/form-data; boundary=b"}, "the form has no file field 'file'"),
])
def test_malformed_forms_are_400(client, unchanged, body, headers, message):
    r = client.post("/api/projects", content=body, headers=headers)
    assert r.status_code == 400 and message in r.json()["detail"]


def test_bad_form_fields_are_400_and_leave_nothing(client, unchanged):
    data = shared_clip(CLIP).read_bytes()
    r = post_file(client, CLIP, data, preset="ultra")
    assert r.status_code == 400 and "unknown preset 'ultra'" in r.json()["detail"]
    r = post_file(client, CLIP, data, mode="smell")
    assert r.status_code == 400 and "mode" in r.json()["detail"]
    r = post_file(client, CLIP, data, generate="maybe")
    assert r.status_code == 400 and "'generate'" in r.json()["detail"]


@pytest.mark.parametrize("raw_name, shown", [
    (b"../../../../etc/passwd.webm", "passwd.webm"),
    (b"..\\..\\windows\\evil.webm", "evil.webm"),
    (b"a\x00b/../\x07c\x1b[31m.webm", "c[31m.webm"),
    (b"..", "untitled"),
    ("\u202efilm\u200b.webm".encode(), "film.webm"),
])
def test_hostile_file_names_only_become_display_names(client, root, raw_name, shown):
    data = shared_clip(CLIP).read_bytes()
    boundary = uuid.uuid4().hex
    body = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"generate\"\r\n\r\nfalse\r\n"
            f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"").encode() + raw_name + \
        b"\"\r\nContent-Type: video/webm\r\n\r\n" + data + f"\r\n--{boundary}--\r\n".encode()
    before = {p for p in root.rglob("*")}
    r = client.post("/api/projects", content=body, headers={"Content-Type": f"multipart/form-data; boundary={boundary}"})
    assert r.status_code == 201, r.text
    project = r.json()
    assert project["name"] == shown and project["source"]["name"] == shown
    new = sorted(str(p.relative_to(root)) for p in set(root.rglob("*")) - before)
    assert new == [f"data/projects/{project['id']}", f"data/projects/{project['id']}/{new[-1].rsplit('/', 1)[-1]}"]
    assert re.fullmatch(r"[0-9a-f]{32}\.webm", new[-1].rsplit("/", 1)[-1])
    assert client.get(f"/api/projects/{project['id']}/media").content == data
    assert client.delete(f"/api/projects/{project['id']}").status_code == 204


def test_name_field_is_sanitised(client):
    data = shared_clip(CLIP).read_bytes()
    r = post_file(client, CLIP, data, name="../My\x00 cut\n", generate="false")
    assert r.status_code == 201 and r.json()["name"] == "../My cut"
    client.delete(f"/api/projects/{r.json()['id']}")


@pytest.mark.parametrize("path", ["/api/projects/" + "0" * 32, "/api/projects/ABC/timeline",
                                  "/api/projects/x.y/media", "/api/jobs/" + "f" * 32, "/api/jobs/nope/events"])
def test_unknown_or_malformed_ids_are_404(client, unchanged, path):
    r = client.get(path)
    assert r.status_code == 404 and r.json()["detail"].startswith("no ")
    assert client.get("/api/projects/..%2F..%2Fetc").status_code == 404


def test_edits_need_a_timeline_and_valid_ops(client, unchanged):
    pid = None
    try:
        r = post_file(client, CLIP, shared_clip(CLIP).read_bytes(), generate="false")
        pid = r.json()["id"]
        assert client.get(f"/api/projects/{pid}/timeline").status_code == 404
        op = {"op": "set", "lanes": ["A1"], "t0": 0, "t1": 2, "value": 1}
        r = client.post(f"/api/projects/{pid}/edits", json={"base_revision": 0, "op": op})
        assert r.status_code == 409 and "no timeline yet" in r.json()["detail"]
        r = client.post(f"/api/projects/{pid}/edits", json={"base_revision": 0, "op": {**op, "lanes": ["A0"]}})
        assert r.status_code == 400 and "field 'lanes' has unknown lane 'A0'" in r.json()["detail"]
        r = client.post(f"/api/projects/{pid}/edits", json={"op": op})
        assert r.status_code == 400 and r.json()["detail"].startswith("field 'base_revision'")
        r = client.post(f"/api/projects/{pid}/undo", json={"base_revision": 0})
        assert r.status_code == 409 and r.json()["detail"] == "nothing to undo"
        r = client.patch(f"/api/projects/{pid}", json={"colour": "red"})
        assert r.status_code == 400 and "colour" in r.json()["detail"]
        r = client.post(f"/api/projects/{pid}/generate", content=b"{not json", headers={"Content-Type": "application/json"})
        assert r.status_code == 400
        assert client.get(f"/api/projects/{pid}/edits").json() == {"revision": 0, "cursor": 0, "ops": [], "markers": []}
    finally:
        if pid:
            client.delete(f"/api/projects/{pid}")


def test_import_refuses_garbage(client):
    r = post_file(client, CLIP, shared_clip(CLIP).read_bytes(), generate="false")
    pid = r.json()["id"]
    try:
        r = client.post(f"/api/projects/{pid}/import", files={"file": ("t.json", b"{\"format\": 1}", "application/json")})
        assert r.status_code == 400 and r.json()["detail"].startswith("t.json: not an autohaptics timeline")
        r = client.post(f"/api/projects/{pid}/import", files={"file": ("t.json", json.dumps({}).encode())},
                        data={"base_revision": "x"})
        assert r.status_code == 400 and "base_revision" in r.json()["detail"]
    finally:
        client.delete(f"/api/projects/{pid}")
