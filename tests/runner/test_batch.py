"""``autohaptics batch`` and :func:`autohaptics.batch.run_batch`: many films, skipping what is done,
failures reported at the end, local worker processes or a Dask cluster with the same results."""

from __future__ import annotations

import csv
import json
import os
import signal
import socket
from pathlib import Path

import numpy as np
import psutil
import pytest

from autohaptics.batch import MANIFEST_NAME, collect_inputs, load_manifest, run_batch
from autohaptics.cli.main import main
from autohaptics.errors import ParameterError
from autohaptics.params import resolve_params
from autohaptics.timeline import Timeline

from shared_data import SHARED_CLIPS, shared_clip

SHORT = ("bbb_1s_1280x720_vp8_vorbis.webm", "bbb_1080p60_2s_h264_aac6ch.mp4")


def _fast(**overrides):
    return resolve_params("fast", overrides)


def _shared_sha256(media_dir: Path) -> dict[str, str]:
    with open(media_dir / "MANIFEST.tsv", newline="") as fh:
        return {row["filename"]: row["sha256"] for row in csv.DictReader(fh, delimiter="\t")}


def _corrupt(path: Path) -> Path:
    rng = np.random.default_rng(7)
    path.write_bytes(b"\x00\x00\x00\x18ftypmp42" + rng.integers(0, 256, 50_000, dtype=np.uint8).tobytes())
    return path


def _assert_same_timeline(a: Timeline, b: Timeline) -> None:
    np.testing.assert_array_equal(a.vibration, b.vibration)
    np.testing.assert_array_equal(a.temperature_c, b.temperature_c)
    np.testing.assert_array_equal(a.fans, b.fans)
    assert a.features.keys() == b.features.keys()
    for name in a.features:
        np.testing.assert_array_equal(a.features[name], b.features[name], err_msg=name)
    assert a.source == b.source
    assert a.generator == b.generator


def _mtimes(out: Path) -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in out.glob("*.timeline.json")}


# ------------------------------------------------------------------ the command line
def test_cli_lists_every_failure_and_exits_1_then_0(tmp_path, capsys):
    clip = shared_clip(SHORT[0])
    broken = _corrupt(tmp_path / "broken.mp4")
    empty = tmp_path / "empty.webm"
    empty.write_bytes(b"")
    out = tmp_path / "out"
    fast = ["--preset", "fast", "--mode", "audio", "--quiet"]

    rc = main(["batch", str(clip), str(broken), str(empty), "-o", str(out), *fast])
    err = capsys.readouterr().err
    assert rc == 1, err
    failed = sorted(ln for ln in err.splitlines() if ln.startswith("failed: "))
    assert [ln.split(": ")[1] for ln in failed] == [str(broken), str(empty)], err
    assert all(len(ln.split(": ", 2)[2]) > 0 for ln in failed)
    assert "3 film(s): 1 done, 0 skipped (up to date), 2 failed" in err
    assert "batch " not in err  # --quiet: no progress bar
    assert Timeline.load(out / f"{clip.stem}.timeline.json").generator["mode"] == "audio"

    rc = main(["batch", str(clip), "-o", str(out), *fast])
    err = capsys.readouterr().err
    assert rc == 0, err
    assert "1 film(s): 0 done, 1 skipped (up to date), 0 failed" in err


# ------------------------------------------------------------------ the whole shared folder
@pytest.mark.slow  # about 40 s on two cores: three runs over every shared clip
def test_folder_with_a_corrupt_file_then_skip_then_parameter_change(media_dir, tmp_path, capsys):
    broken = _corrupt(tmp_path / "broken.mp4")
    out = tmp_path / "out"
    expected_sha = _shared_sha256(media_dir)
    assert set(expected_sha) == set(SHARED_CLIPS)

    rc = main(["batch", str(media_dir), str(broken), "-o", str(out), "--jobs", "2"])
    err = capsys.readouterr().err
    assert rc == 1, err
    failed = [ln for ln in err.splitlines() if ln.startswith("failed: ")]
    assert len(failed) == 1 and failed[0].startswith(f"failed: {broken}: "), err
    assert "not a readable media file" in failed[0]
    assert f"{len(SHARED_CLIPS) + 1} film(s): {len(SHARED_CLIPS)} done, 0 skipped (up to date), 1 failed" in err
    assert "batch 100%" in err  # the one overall progress bar (a line per 10 % when stderr is not a terminal)
    manifest = load_manifest(out)
    for clip in SHARED_CLIPS:
        name = Path(clip).stem
        tl = Timeline.load(out / f"{name}.timeline.json")
        assert tl.source["sha256"] == expected_sha[clip]
        assert tl.generator["preset"] == "balanced"
        assert manifest[name]["sha256"] == expected_sha[clip]
        assert manifest[name]["source"] == str(media_dir / clip)
    assert not (out / "broken.timeline.json").exists()
    first = _mtimes(out)

    rc = main(["batch", str(media_dir), str(broken), "-o", str(out), "--jobs", "2"])
    err = capsys.readouterr().err
    assert rc == 1, err
    assert f"0 done, {len(SHARED_CLIPS)} skipped (up to date), 1 failed" in err
    assert _mtimes(out) == first

    rc = main(["batch", str(media_dir), "-o", str(out), "--jobs", "2", "--threshold", "loudness=0.9"])
    err = capsys.readouterr().err
    assert rc == 0, err
    assert f"{len(SHARED_CLIPS)} done, 0 skipped" in err
    for clip in SHARED_CLIPS:
        tl = Timeline.load(out / f"{Path(clip).stem}.timeline.json")
        assert tl.generator["params"]["intensity"]["thresholds"]["loudness"] == 0.9
    assert all(_mtimes(out)[k] != v for k, v in first.items())


# --------------------------------------------------------------------------- skipping
def test_skip_rules_source_content_parameters_and_missing_manifest(tmp_path):
    film = tmp_path / "in" / "film.webm"
    film.parent.mkdir()
    film.symlink_to(shared_clip(SHORT[0]))
    out = tmp_path / "out"
    params, preset = _fast(mode="audio")

    first = run_batch([film.parent], out, params, preset)
    assert [r.status for r in first.results] == ["done"] and first.exit_status == 0
    assert first.results[0].output == out / "film.timeline.json"

    again = run_batch([film.parent], out, params, preset)
    assert [r.status for r in again.results] == ["skipped"]

    (out / MANIFEST_NAME).unlink()  # without the manifest, the timeline itself says what it was made from
    again = run_batch([film.parent], out, params, preset)
    assert [r.status for r in again.results] == ["skipped"]
    assert load_manifest(out)["film"]["sha256"] == Timeline.load(out / "film.timeline.json").source["sha256"]

    (out / MANIFEST_NAME).unlink()
    other, _ = _fast(mode="audio", seed=5)
    changed = run_batch([film.parent], out, other, preset)
    assert [r.status for r in changed.results] == ["done"]
    assert Timeline.load(out / "film.timeline.json").generator["params"]["seed"] == 5

    film.unlink()  # same path, other content
    film.symlink_to(shared_clip(SHORT[1]))
    redone = run_batch([film], out, other, preset)
    assert [r.status for r in redone.results] == ["done"]
    tl = Timeline.load(out / "film.timeline.json")
    assert tl.source["duration_s"] == pytest.approx(2.0, abs=0.05)
    assert load_manifest(out)["film"]["sha256"] == tl.source["sha256"]


def test_name_clashes_get_distinct_names_that_stay(tmp_path):
    a, b, c = (tmp_path / d for d in "abc")
    clips = ((a, SHORT[0], "clip.webm"), (b, "sintel_trailer_640x272_vp8_vorbis.webm", "clip.webm"),
             (c, SHORT[1], "clip.mp4"))
    for folder, clip, name in clips:
        folder.mkdir()
        (folder / name).symlink_to(shared_clip(clip))
    out = tmp_path / "out"
    params, preset = _fast(mode="audio")

    solo = run_batch([b / "clip.webm"], out, params, preset)
    assert solo.results[0].output == out / "clip.timeline.json"

    report = run_batch([a, b, c], out, params, preset)
    outputs = {r.source: r.output for r in report.results}
    assert len(set(outputs.values())) == 3
    assert outputs[b / "clip.webm"] == out / "clip.timeline.json"  # keeps the name of the earlier run
    assert {r.source: r.status for r in report.results} == {
        a / "clip.webm": "done", b / "clip.webm": "skipped", c / "clip.mp4": "done"}
    for src, output in outputs.items():
        assert output.name.startswith("clip") and output.name.endswith(".timeline.json")
        assert Timeline.load(output).source["name"] == src.name

    again = run_batch([a, b, c], out, params, preset)
    assert {r.source: r.output for r in again.results} == outputs
    assert [r.status for r in again.results] == ["skipped"] * 3


# --------------------------------------------------------------------------- inputs
def test_collect_inputs_folders_globs_and_duplicates(media_dir):
    films = collect_inputs([media_dir, media_dir / SHORT[0], str(media_dir / "bbb_1*.webm")])
    assert [p.name for p in films] == SHARED_CLIPS  # MANIFEST.tsv is not a film; no duplicates
    assert [p.name for p in collect_inputs([str(media_dir / "*.mp4")])] == [c for c in SHARED_CLIPS
                                                                          if c.endswith(".mp4")]
    with pytest.raises(ParameterError, match="matches no file"):
        collect_inputs([str(media_dir / "*.nothing")])
    with pytest.raises(ParameterError, match="no such file or folder"):
        collect_inputs([media_dir / "missing.mp4"])


def test_usage_errors_exit_2(tmp_path, media_dir, capsys):
    clip = str(media_dir / SHORT[0])
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "notes.txt").write_text("no films here")
    a_file = tmp_path / "file"
    a_file.write_text("")
    cases = {
        "no such file": [str(tmp_path / "nope.mp4"), "-o", str(tmp_path / "o")],
        "no media files found": [str(empty), "-o", str(tmp_path / "o")],
        "jobs must be": [clip, "-o", str(tmp_path / "o"), "--jobs", "0"],
        "tcp://HOST:PORT": [clip, "-o", str(tmp_path / "o"), "--scheduler", "localhost"],
        "--jobs is for local runs": [clip, "-o", str(tmp_path / "o"), "--jobs", "2", "--scheduler", "tcp://x:1"],
        "is not a folder": [clip, "-o", str(a_file)],
        "unknown parameter": [clip, "-o", str(tmp_path / "o"), "--set", "nosuch.knob=1"],
    }
    for message, args in cases.items():
        assert main(["batch", *args]) == 2, message
        err = capsys.readouterr().err
        assert err.startswith("autohaptics: error: ") and message in err, err
    assert not (tmp_path / "o").exists()
    with pytest.raises(SystemExit) as exc:
        main(["batch", clip])  # -o is required
    assert exc.value.code == 2


# ------------------------------------------------------------------- dying workers
def _killer(clip: Path, kills: int):
    """A progress callback that SIGKILLs the worker process that has ``clip`` open, ``kills`` times
    (a worker of the pool: a child of this process, not a child of the worker that reads it too)."""
    me = psutil.Process()
    state = {"left": kills, "fractions": [], "killed": set()}

    def progress(stage: str, fraction: float) -> None:
        state["fractions"].append(fraction)
        if state["left"] <= 0:
            return
        for child in me.children():
            if child.pid in state["killed"]:  # a killed process can list its files until it is gone
                continue
            try:
                if any(f.path == str(clip) for f in child.open_files()):
                    os.kill(child.pid, signal.SIGKILL)
                    state["killed"].add(child.pid)
                    state["left"] -= 1
                    return
            except psutil.Error:
                continue

    return progress, state


@pytest.mark.parametrize("kills, status", [(1, "done"), (2, "failed")])
def test_a_dying_worker_is_replaced_and_a_film_that_kills_two_is_reported(tmp_path, kills, status):
    target = shared_clip("bbb_opening_30s_1280x720_vp8_vorbis.webm")
    waiting = shared_clip("sintel_trailer_480x204_h264_aac.mp4")
    params, preset = _fast(mode="audio")
    progress, state = _killer(target, kills)

    report = run_batch([target, waiting], tmp_path / "out", params, preset, jobs=1, progress=progress)

    assert state["left"] == 0, "the worker analysing the clip was never seen with it open"
    by_name = {r.source.name: r for r in report.results}
    assert by_name[waiting.name].status == "done"  # it waited behind the dying film, it is not charged
    assert by_name[target.name].status == status
    if status == "failed":
        assert by_name[target.name].reason == "the worker process died while analysing it (2 times)"
        assert report.exit_status == 1
    else:
        Timeline.load(by_name[target.name].output)
        assert report.exit_status == 0


# ------------------------------------------------------------------------------ Dask
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def environ_restored():
    """distributed's LocalCluster writes its worker settings (MALLOC_TRIM_THRESHOLD_, OMP_NUM_THREADS=1,
    PYTHONHASHSEED, ...) into this process's os.environ, where every later subprocess of the session
    would inherit them: put the environment back."""
    saved = dict(os.environ)
    yield
    os.environ.clear()
    os.environ.update(saved)


def test_dask_cluster_gives_the_local_timelines(tmp_path, capsys, environ_restored):
    distributed = pytest.importorskip("distributed")
    clips = [shared_clip(c) for c in (*SHORT, "sintel_trailer_480x204_h264_aac.mp4")]
    broken = _corrupt(tmp_path / "broken.mp4")
    params, preset = resolve_params("fast")

    local = run_batch([*clips, broken], tmp_path / "local", params, preset, jobs=2)
    fractions: list[float] = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  scheduler_port=_free_port(), dashboard_address=None) as cluster:
        remote = run_batch([*clips, broken], tmp_path / "dask", params, preset, scheduler=cluster.scheduler_address,
                           progress=lambda stage, f: fractions.append(f))
        # the command line on the same cluster: everything done is skipped, the broken file fails again
        rc = main(["batch", *map(str, clips), str(broken), "-o", str(tmp_path / "dask"), "--preset", "fast",
                   "--scheduler", cluster.scheduler_address, "--quiet"])
        assert rc == 1
        assert f"0 done, {len(clips)} skipped (up to date), 1 failed" in capsys.readouterr().err

    for report in (local, remote):
        # results come in the sorted order of the sources' paths, which depends on where the clips and
        # tmp_path live: compare by name
        seen = {r.source.name: r for r in report.results}
        assert sorted(seen) == sorted([c.name for c in clips] + [broken.name]), seen
        assert {n: r.status for n, r in seen.items()} == {
            **{c.name: "done" for c in clips}, broken.name: "failed"}, \
            [(r.source.name, r.status, r.reason) for r in report.results]
        assert "not a readable media file" in seen[broken.name].reason, seen[broken.name].reason
    assert [r.reason for r in remote.failed] == [r.reason for r in local.failed]
    for a, b in zip(local.done, remote.done):
        assert a.output.name == b.output.name
        _assert_same_timeline(Timeline.load(a.output), Timeline.load(b.output))
    assert fractions[-1] == 1.0 and fractions == sorted(fractions), fractions
    # more distinct values than film completions: the workers' progress within films came back
    assert len(set(fractions)) > len(clips) + 2, fractions
    manifest = json.loads((tmp_path / "dask" / MANIFEST_NAME).read_text())
    assert manifest["films"] == {
        k: {**v, "finished_at": manifest["films"][k]["finished_at"]} for k, v in load_manifest(tmp_path / "local").items()}
