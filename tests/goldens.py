"""Golden outputs: what the CLI writes for the shared clips, kept to prove that a restructuring
changes nothing.

Each case runs ``autohaptics generate CLIP --preset P --mode M`` with every stage on the thesis's
own rule (``--set`` each of ``params.THESIS_RULES``: the goldens were written before the defaults
moved away from the thesis, and these rules must go on reproducing them) and keeps its canonical form (the
timeline JSON with the timing figures of ``stats`` left out; every other byte counts). The export
goldens run ``autohaptics export`` in every format on the stored golden timelines, so they depend
on the exporters only. ``tests/pipeline/test_golden.py`` checks both.

Write them again (after a change that is MEANT to change outputs, said in its commit message)::

    .venv/bin/python tests/goldens.py --write            # every case
    .venv/bin/python tests/goldens.py --write --exports  # the export digests only
"""

from __future__ import annotations

import argparse
import gzip
import hashlib
import json
import sys
import tempfile
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
GOLDEN = HERE / "golden"
sys.path.insert(0, str(HERE))

from shared_data import MEDIA  # noqa: E402

from autohaptics.bench.common import environment  # noqa: E402

PRESETS = ("reference", "balanced", "fast")
MODES = ("multimodal", "audio", "visual", "random")
SHORT_CLIPS = ("bbb_1s_1280x720_vp8_vorbis.webm", "bbb_1080p60_2s_h264_aac6ch.mp4")
LONG_CLIP = "sintel_trailer_480x204_h264_aac.mp4"
# every preset and mode on the short clips; the modes of the default preset and the other presets'
# multimodal run on the long one
CASES = tuple([(c, p, m) for c in SHORT_CLIPS for p in PRESETS for m in MODES]
              + [(LONG_CLIP, "balanced", m) for m in MODES]
              + [(LONG_CLIP, p, "multimodal") for p in ("reference", "fast")])
EXPORT_CASES = (("bbb_1080p60_2s_h264_aac6ch.mp4", "balanced", "multimodal"),
                (LONG_CLIP, "balanced", "multimodal"), (LONG_CLIP, "balanced", "visual"))
EXPORT_FORMATS = ("csv", "json", "ahap", "hjif", "mpegv")
EXPORT_DATE = "2026-01-01"


def case_name(clip: str, preset: str, mode: str) -> str:
    return f"{Path(clip).stem}.{preset}.{mode}"


def golden_path(clip: str, preset: str, mode: str) -> Path:
    return GOLDEN / f"{case_name(clip, preset, mode)}.timeline.json.gz"


def _cli(argv: list[str]) -> None:
    from autohaptics.cli.main import main

    rc = main(argv)
    if rc != 0:
        raise RuntimeError(f"autohaptics {' '.join(argv)} exited {rc}")


def _drop_timings(obj):
    """``obj`` without the keys that hold measured times (the name says seconds)."""
    if isinstance(obj, dict):
        return {k: _drop_timings(v) for k, v in obj.items() if "seconds" not in k}
    if isinstance(obj, list):
        return [_drop_timings(v) for v in obj]
    return obj


def canonical(doc: dict) -> bytes:
    """The timeline document with timing figures left out, as compact sorted JSON bytes."""
    doc = dict(doc)
    doc["stats"] = _drop_timings(doc.get("stats", {}))
    return json.dumps(doc, sort_keys=True, separators=(",", ":")).encode("utf-8")


def _restrict(actual, golden):
    """``actual`` with the dict keys that ``golden`` lacks left out, at every depth."""
    if isinstance(actual, dict) and isinstance(golden, dict):
        return {k: _restrict(v, golden[k]) for k, v in actual.items() if k in golden}
    return actual


def as_written(actual: bytes, golden: bytes) -> bytes:
    """The canonical ``actual`` without the parameters and statistics added since ``golden`` was
    written (``generator.params`` and ``stats`` restricted to the golden's keys); every other field
    and every track stays, so a changed output still differs."""
    a, g = json.loads(actual), json.loads(golden)
    a["generator"]["params"] = _restrict(a["generator"]["params"], g["generator"]["params"])
    a["stats"] = _restrict(a["stats"], g["stats"])
    return json.dumps(a, sort_keys=True, separators=(",", ":")).encode("utf-8")


def generate(clip: str, preset: str, mode: str, workdir: Path) -> bytes:
    """The canonical timeline that ``autohaptics generate`` writes for this case now."""
    out = workdir / f"{case_name(clip, preset, mode)}.json"
    from autohaptics.params import THESIS_RULES

    thesis = [a for k, v in THESIS_RULES.items() for a in ("--set", f"{k}={v}")]
    _cli(["generate", str(MEDIA / clip), "-o", str(out), "--preset", preset, "--mode", mode, "--quiet", *thesis])
    return canonical(json.loads(out.read_text(encoding="utf-8")))


def load_golden(clip: str, preset: str, mode: str) -> bytes:
    return gzip.decompress(golden_path(clip, preset, mode).read_bytes())


def export_digests(timeline_bytes: bytes, workdir: Path) -> dict[str, dict[str, str]]:
    """{format: {file: sha256}} of ``autohaptics export`` in every format on a timeline; a zip
    counts by its members' names and contents (its entries' dates are the export's)."""
    src = workdir / "golden.timeline.json"
    src.write_bytes(timeline_bytes)
    out: dict[str, dict[str, str]] = {}
    for fmt in EXPORT_FORMATS:
        dest = workdir / f"export.{fmt}"
        _cli(["export", str(src), "--format", fmt, "-o", str(dest), "--date", EXPORT_DATE])
        if zipfile.is_zipfile(dest):
            with zipfile.ZipFile(dest) as z:
                out[fmt] = {i.filename: hashlib.sha256(z.read(i)).hexdigest() for i in z.infolist()}
        else:
            out[fmt] = {dest.name: hashlib.sha256(dest.read_bytes()).hexdigest()}
    return out


def write(*, exports_only: bool = False) -> None:
    GOLDEN.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if not exports_only:
            for case in CASES:
                golden_path(*case).write_bytes(gzip.compress(generate(*case, work), mtime=0))
                print("wrote", golden_path(*case).name, file=sys.stderr)
            (GOLDEN / "environment.json").write_text(json.dumps(environment(), indent=1, sort_keys=True) + "\n")
        digests = {case_name(*c): export_digests(load_golden(*c), work) for c in EXPORT_CASES}
        (GOLDEN / "exports.json").write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n")
        print("wrote exports.json", file=sys.stderr)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", action="store_true", required=True)
    ap.add_argument("--exports", action="store_true", help="only the export digests")
    a = ap.parse_args()
    write(exports_only=a.exports)
