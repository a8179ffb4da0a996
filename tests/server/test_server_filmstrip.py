"""Filmstrip tiles and posters through the server, on a letterboxed film whose every tick is one
flat grey frame of its own level (30 + 3 x tick): the tile geometry (the active picture's aspect at
45 px, 16 frames a tile, the last tile narrower), each frame the picture of its tick, 404s with one
sentence, immutable caching headers, the pictures made ahead after the generate, the cache bound
evicting the oldest files, and the project's removal removing them. The pictures made ahead come
from a separate nice-19 process: never this process's picture maker, no folder left after a removal
during the work, the process restarted after it dies and gone once the server stops."""

from __future__ import annotations

import logging
import os
import signal
import time
from fractions import Fraction
from pathlib import Path

import cv2
import numpy as np
import pytest

from autohaptics.server import posters
from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings
from autohaptics.testing import Scene, Segment, write_scene
from service_client import LocalClient

N_TICKS = 70
FRAME_W = 90  # the active picture is 96 x 48 (2:1) inside a 96 x 72 frame: 90 x 45


def level(tick: int) -> int:
    return 30 + 3 * tick


def ticking_film(path: Path) -> Path:
    scene = Scene(N_TICKS / 10, background=tuple(
        Segment(t / 10, (t + 1) / 10, (level(t),) * 3) for t in range(N_TICKS)), name="ticks")
    return write_scene(path, scene, width=96, height=72, fps=10, picture=(0, 12, 96, 48), audio=False)


def make_client(tmp_path_factory, **settings):
    data = tmp_path_factory.mktemp("server-filmstrip") / "data"
    return LocalClient(create_app(Settings(data_dir=data, frontend_dir=None, **settings))), data


def new_project(client, film: Path) -> str:
    pid = client.generated_project(film)["id"]
    assert client.get(f"/api/projects/{pid}/filmstrip").status_code == 200  # asks for the pictures ahead
    assert client.app.state.pictures.wait_idle(60)  # (the job's end asked too: both are done)
    return pid


@pytest.fixture(scope="module")
def film(tmp_path_factory) -> Path:
    return ticking_film(tmp_path_factory.mktemp("film") / "ticks.mp4")


@pytest.fixture(scope="module")
def served(tmp_path_factory, film):
    client, data = make_client(tmp_path_factory)
    with client:
        yield client, data, new_project(client, film)


def frames(jpeg: bytes) -> np.ndarray:
    """The mean grey level of each frame of a tile."""
    img = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_GRAYSCALE)
    assert img.shape[0] == 45 and img.shape[1] % FRAME_W == 0, img.shape
    return img.reshape(45, -1, FRAME_W)[5:-5, :, 10:-10].mean(axis=(0, 2))


def test_the_geometry_follows_the_active_picture_and_the_length(served):
    client, _, pid = served
    r = client.get(f"/api/projects/{pid}/filmstrip")
    assert r.status_code == 200, r.text
    assert r.json() == {"frame_w": FRAME_W, "frame_h": 45, "per_tile": 16, "steps": [1, 2, 4, 8]}


@pytest.mark.parametrize("step, tiles", [(1, 5), (2, 3), (4, 2), (8, 1)])
def test_every_frame_is_the_picture_of_its_tick(served, step, tiles):
    client, _, pid = served
    for tile in range(tiles):
        r = client.get(f"/api/projects/{pid}/filmstrip/{step}/{tile}.jpg")
        assert r.status_code == 200 and r.headers["content-type"] == "image/jpeg", r.text
        assert r.headers["cache-control"] == "public, max-age=31536000, immutable"
        ticks = list(range(16 * tile * step, min(16 * (tile + 1) * step, N_TICKS), step))
        found = frames(r.content)
        assert len(found) == len(ticks)  # the last tile is narrower
        np.testing.assert_allclose(found, [level(t) for t in ticks], atol=1.2)


def test_out_of_range_steps_and_tiles_are_404_with_one_sentence(served):
    client, _, pid = served
    for url, words in ((f"filmstrip/3/0.jpg", "step 3 is not one of this filmstrip's steps (1, 2, 4, 8)"),
                       (f"filmstrip/16/0.jpg", "step 16 is not one of"),
                       (f"filmstrip/0/0.jpg", "step 0 is not one of"),
                       (f"filmstrip/1/5.jpg", "tile 5 is not in this filmstrip at step 1 (0..4)"),
                       (f"filmstrip/8/1.jpg", "tile 1 is not in this filmstrip at step 8 (0..0)"),
                       (f"filmstrip/1/-1.jpg", "tile -1 is not in"),
                       (f"posters/{N_TICKS}.jpg", f"tick {N_TICKS} is not in this film's timeline")):
        r = client.get(f"/api/projects/{pid}/{url}")
        assert r.status_code == 404, (url, r.text)
        assert r.json()["detail"].startswith(words) and r.json()["detail"].count(". ") == 0
    assert client.get(f"/api/projects/{pid}/filmstrip/one/0.jpg").status_code == 400
    assert client.get(f"/api/projects/{'0' * 32}/filmstrip").status_code == 404
    assert client.get(f"/api/projects/{'0' * 32}/filmstrip/1/0.jpg").status_code == 404


def test_posters_show_their_tick_at_the_pictures_aspect(served):
    client, _, pid = served
    for tick in (0, 33, N_TICKS - 1):
        r = client.get(f"/api/projects/{pid}/posters/{tick}.jpg")
        img = cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_GRAYSCALE)
        assert img.shape == (80, 160) and abs(img[10:-10, 10:-10].mean() - level(tick)) < 1.2


def test_an_anamorphic_films_posters_show_it_as_it_is_shown(tmp_path):
    """A PAL DVD's 720 x 576 picture with pixels 64/45 wide shows 16:9: its posters are 160 x 90 (they
    were 160 x 128, squeezed), and a disc round on screen is round in them."""
    from autohaptics.testing import Shape
    from autohaptics.testing.reencode import reencode

    scene = Scene(1.0, background=(Segment(0, 1.0, (200, 180, 160)),),
                  shapes=(Shape("circle", (20, 20, 200), t_on=0, t_off=1.0, xy0=(0.5, 0.5), size0=(0.2, 0.35)),))
    wide = write_scene(tmp_path / "wide.mp4", scene, width=320, height=180, fps=25, audio=False)
    dvd = reencode(wide, tmp_path / "dvd.mkv", width=720, height=576, pixel_aspect=Fraction(64, 45),
                   video_codec="mpeg2video", video_bit_rate=6_000_000)
    source = posters.film(dvd, tmp_path / "no-analysis.npz")
    assert posters.poster_size(source) == (160, 90)
    img = cv2.imdecode(np.frombuffer(posters.picture_jpeg(source, [5], (160, 90)), np.uint8), cv2.IMREAD_COLOR)
    ys, xs = np.nonzero((img[..., 0] > 150) & (img[..., 2] < 90))  # BGR: the blue disc
    assert img.shape[:2] == (90, 160) and abs(int(xs.max() - xs.min()) - int(ys.max() - ys.min())) <= 3


def test_a_3d_films_posters_show_one_view_as_it_is_shown(tmp_path):
    """A 16:9 film packed half side by side (3D): its posters show the left view, stretched back to 16:9
    (160 x 90, not the 80:90 view as stored), and a disc round on screen is round in them."""
    from autohaptics import pipeline
    from autohaptics.testing import Shape
    from autohaptics.testing.stereo import write_packed

    scene = Scene(2.0, background=(Segment(0, 2.0, (200, 180, 160)),),
                  shapes=(Shape("circle", (20, 20, 200), t_on=0, t_off=2.0, xy0=(0.5, 0.5), size0=(0.2, 0.35)),))
    flat = write_scene(tmp_path / "flat.mp4", scene, width=320, height=180, fps=25, audio=False)
    sbs = write_packed(flat, tmp_path / "sbs.mkv", "side_by_side")
    pipeline.analyse(sbs).save(tmp_path / "sbs.npz")
    source = posters.film(sbs, tmp_path / "sbs.npz")
    assert source.crop == (0, 0, 160, 180) and posters.poster_size(source) == (160, 90)
    img = cv2.imdecode(np.frombuffer(posters.picture_jpeg(source, [5], (160, 90)), np.uint8), cv2.IMREAD_COLOR)
    ys, xs = np.nonzero((img[..., 0] > 150) & (img[..., 2] < 90))  # BGR: the blue disc
    assert img.shape[:2] == (90, 160) and abs(int(xs.max() - xs.min()) - int(ys.max() - ys.min())) <= 3
    assert xs.min() > 40 and xs.max() < 120  # one disc, in the middle: one view


def test_the_pictures_are_made_ahead_and_kept_on_disk(served):
    client, data, pid = served
    assert client.app.state.pictures.wait_idle(60)
    folder = data / "projects" / pid
    tiles = {p.name for p in (folder / "filmstrip").glob("*.jpg")}
    assert {"8-0.jpg", "4-0.jpg", "4-1.jpg", "1-4.jpg"} <= tiles  # every step: the film has few frames
    shots = client.get(f"/api/projects/{pid}/shots").json()["shots"]
    assert {p.name for p in (folder / "posters").glob("*.jpg")} >= {s["poster_url"].rsplit("/", 1)[1] for s in shots}
    before = (folder / "filmstrip" / "2-1.jpg").read_bytes()
    assert client.get(f"/api/projects/{pid}/filmstrip/2/1.jpg").content == before  # served from the disk


def test_the_cache_bound_evicts_the_oldest_and_removal_removes_everything(tmp_path_factory, film):
    client, data = make_client(tmp_path_factory, picture_cache_bytes=6000)
    with client:
        pid = new_project(client, film)
        pictures = client.app.state.pictures
        assert pictures.wait_idle(60)
        folder = data / "projects" / pid
        for tile in range(5):
            assert client.get(f"/api/projects/{pid}/filmstrip/1/{tile}.jpg").status_code == 200
            time.sleep(0.01)  # distinct modification times
        on_disk = sorted((p.stat().st_mtime_ns, p.name, p.stat().st_size)
                         for d in ("posters", "filmstrip") for p in (folder / d).glob("*.jpg"))
        assert 0 < sum(s for *_, s in on_disk) <= 6000 and pictures.used_bytes(pid) == sum(s for *_, s in on_disk)
        assert on_disk[-1][1] == "1-4.jpg" and "1-0.jpg" not in {name for _, name, _ in on_disk}  # oldest went
        assert len(on_disk) < 5 + 4 + 3 + 2 + 1
        r = client.get(f"/api/projects/{pid}/filmstrip/1/0.jpg")  # evicted: made again
        assert r.status_code == 200 and len(frames(r.content)) == 16
        assert client.delete(f"/api/projects/{pid}").status_code == 204
        assert not folder.exists()
        assert pictures.wait_idle(10) and not folder.exists()


def test_the_pictures_wait_while_a_generate_job_runs(tmp_path_factory, film):
    client, data = make_client(tmp_path_factory)
    with client:
        pid = new_project(client, film)
        pictures = client.app.state.pictures
        assert pictures.wait_idle(60)
        r = client.post(f"/api/projects/{pid}/duplicate")
        other = r.json()["id"]
        folder = data / "projects" / other
        assert not (folder / "filmstrip").exists()  # a copy starts without pictures
        r = client.post(f"/api/projects/{pid}/generate", json={"overrides": {"video.active_area": "full"}})  # analyses
        assert r.status_code == 202, r.text
        job = r.json()["job"]["id"]
        assert client.get(f"/api/projects/{other}/filmstrip").status_code == 200  # asks for them ahead
        looks = 0
        while True:
            made = [p for d in ("posters", "filmstrip") for p in (folder / d).glob("*.jpg")]
            if client.get(f"/api/jobs/{job}").json()["status"] not in ("queued", "running"):
                break
            assert not made, "a picture was made while a job ran"
            looks += 1
            time.sleep(0.05)
        assert client.finished_job(job)["status"] == "done" and looks >= 1  # it looked while the job ran
        assert pictures.wait_idle(60)
        assert (folder / "filmstrip" / "8-0.jpg").exists() and (folder / "posters").is_dir()


def test_a_busy_server_makes_nothing_ahead_until_it_is_free(served, tmp_path_factory):
    """The background maker itself, over the server's store: nothing while ``busy()``, all after."""
    import threading

    from autohaptics.server.pictures import Pictures

    client, data, pid = served
    other = client.post(f"/api/projects/{pid}/duplicate").json()["id"]
    busy = threading.Event()
    busy.set()
    maker = Pictures(client.app.state.store, client.app.state.composer, bound_bytes=10**8, busy=busy.is_set)
    try:
        maker.ahead(other)
        assert not maker.wait_idle(1.5)  # still waiting
        folder = data / "projects" / other
        assert not list(folder.glob("*/*.jpg"))
        busy.clear()
        assert maker.wait_idle(60)
        assert len(list((folder / "filmstrip").glob("*.jpg"))) == 5 + 3 + 2 + 1
    finally:
        maker.close()


def first_picture(folder: Path, timeout_s: float = 60.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not list(folder.glob("*/*.jpg")):
        assert time.monotonic() < deadline, "no picture was made ahead"
        time.sleep(0.02)


def alive(pid: int) -> bool:
    return Path(f"/proc/{pid}").exists()


def dead(child: int) -> bool:
    """This process's child has ended, every thread of it (it can be waited for; left unwaited for
    its owner: a killed process's main thread is a zombie while its other threads still exit)."""
    try:
        return os.waitid(os.P_PID, child, os.WEXITED | os.WNOHANG | os.WNOWAIT) is not None
    except ChildProcessError:  # already waited for
        return True


def test_the_pictures_ahead_come_from_a_nice_process_that_stops_with_the_server(tmp_path_factory, film,
                                                                                 monkeypatch):
    made_here = []
    own = posters.picture_jpeg
    monkeypatch.setattr(posters, "picture_jpeg", lambda *a, **k: made_here.append(a[1]) or own(*a, **k))
    client, data = make_client(tmp_path_factory)
    with client:
        pictures = client.app.state.pictures
        assert pictures.maker.pid is None  # started on the first picture
        pid = new_project(client, film)
        child = pictures.maker.pid
        assert child is not None and child != os.getpid() and alive(child)
        assert os.getpriority(os.PRIO_PROCESS, child) == 19
        folder = data / "projects" / pid
        assert len(list((folder / "filmstrip").glob("*.jpg"))) == 5 + 3 + 2 + 1
        assert list((folder / "posters").glob("*.jpg"))
        assert made_here == []  # every one of them made by the other process
        (folder / "filmstrip" / "2-1.jpg").unlink()
        assert client.get(f"/api/projects/{pid}/filmstrip/2/1.jpg").status_code == 200
        assert made_here == [[32, 34, 36, 38, 40, 42, 44, 46, 48, 50, 52, 54, 56, 58, 60, 62]]  # on demand: here
        assert list(folder.glob("*/*.tmp")) == []
    assert not alive(child) and pictures.maker.pid is None


def test_removing_a_project_while_its_pictures_are_made_ahead_leaves_no_folder(tmp_path_factory, film):
    client, data = make_client(tmp_path_factory)
    with client:
        pictures = client.app.state.pictures
        pictures.maker.pause_s = 0.3  # each picture waits before it is written
        r = client.post("/api/projects", files={"file": ("ticks.mp4", film.read_bytes(), "video/mp4")})
        pid, folder = r.json()["id"], data / "projects" / r.json()["id"]
        assert client.finished_job(r.json()["job"]["id"])["status"] == "done"
        first_picture(folder)
        child = pictures.maker.pid
        assert client.delete(f"/api/projects/{pid}").status_code == 204
        assert not folder.exists()
        time.sleep(1.0)  # longer than a picture's wait: nothing arrives late
        assert pictures.wait_idle(10) and not folder.exists()
        assert pictures.maker.pid == child and alive(child)  # the picture was cancelled, the process kept


def test_a_picture_process_that_dies_is_logged_and_started_again(tmp_path_factory, film, caplog):
    client, data = make_client(tmp_path_factory)
    with client, caplog.at_level(logging.WARNING, logger="autohaptics.server.pictures"):
        pictures = client.app.state.pictures
        pictures.maker.pause_s = 0.3
        r = client.post("/api/projects", files={"file": ("ticks.mp4", film.read_bytes(), "video/mp4")})
        pid, folder = r.json()["id"], data / "projects" / r.json()["id"]
        assert client.finished_job(r.json()["job"]["id"])["status"] == "done"
        first_picture(folder)
        child = pictures.maker.pid
        os.kill(child, signal.SIGKILL)
        assert pictures.wait_idle(30)
        assert "pictures not made ahead (the picture process stopped" in caplog.text
        assert len(list((folder / "filmstrip").glob("*.jpg"))) < 5 + 3 + 2 + 1  # that work was dropped
        assert client.get(f"/api/projects/{pid}/shots").status_code == 200  # the server answers, asks again
        pictures.maker.pause_s = 0.0
        assert pictures.wait_idle(60)
        assert pictures.maker.pid not in (None, child)
        assert len(list((folder / "filmstrip").glob("*.jpg"))) == 5 + 3 + 2 + 1


def test_a_picture_process_that_died_between_pictures_is_reported_then_started_again(film, tmp_path):
    """The maker alone: a child killed while no picture was on its way is reported by the next
    picture (the planner logs it and drops that project's work, as for a death during a picture),
    and the one after starts a new child."""
    from autohaptics.server.ahead import AheadMaker, MakerGone

    maker = AheadMaker()
    source = posters.film(film, tmp_path / "no-analysis.npz")
    (tmp_path / "posters").mkdir()
    size = posters.poster_size(source)
    try:
        assert maker.make(tmp_path / "posters" / "3.jpg", source, [3], size) > 0
        child = maker.pid
        os.kill(child, signal.SIGKILL)
        deadline = time.monotonic() + 30
        while not dead(child):
            assert time.monotonic() < deadline, "the killed picture process did not end"
            time.sleep(0.01)
        with pytest.raises(MakerGone, match="between pictures"):
            maker.make(tmp_path / "posters" / "4.jpg", source, [4], size)
        assert maker.pid is None and not (tmp_path / "posters" / "4.jpg").exists()
        assert maker.make(tmp_path / "posters" / "4.jpg", source, [4], size) > 0
        assert maker.pid not in (None, child)
    finally:
        maker.close()


def test_a_picture_process_that_does_not_stop_is_killed_on_close(film, tmp_path):
    """The maker alone: a child that does not answer cannot hold up the close."""
    import threading

    from autohaptics.server.ahead import AheadMaker, MakerGone

    maker, outcome = AheadMaker(), []
    source = posters.film(film, tmp_path / "no-analysis.npz")
    (tmp_path / "posters").mkdir()

    def make() -> None:
        try:
            outcome.append(maker.make(tmp_path / "posters" / "3.jpg", source, [3], posters.poster_size(source)))
        except MakerGone as exc:
            outcome.append(exc)

    thread = threading.Thread(target=make)
    thread.start()
    while maker.pid is None:
        time.sleep(0.01)
    child = maker.pid
    os.kill(child, signal.SIGSTOP)  # a child that cannot answer, not even to its cancel
    maker.close(timeout_s=1.0)
    thread.join(10)
    assert not thread.is_alive() and isinstance(outcome[0], MakerGone) and not alive(child)
    assert not (tmp_path / "posters" / "3.jpg").exists()
