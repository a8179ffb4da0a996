"""Decode the first audio track (mono mix at 48 kHz), calibrate it to pascal and write the per-frame audio
features as JSON: loudness (ISO 532-1, sone), sharpness (DIN 45692, acum), booming index and low-frequency
energy (Pa^2) on the 20 ms grid.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from typing import TYPE_CHECKING

from autohaptics.outputs import atomic_output, check_output
from autohaptics.progress import ProgressBar

if TYPE_CHECKING:  # imported where used: `autohaptics --help` loads no numpy
    import numpy as np

    from autohaptics import media
    from autohaptics.intensity import features as af

_UNITS = {"t_s": "s", "loudness": "sone", "sharpness": "acum",
          "booming": "sone (hatano) or dimensionless (paper)", "low_energy": "Pa^2"}
_LONG_INPUT_S = 20.0  # inputs longer than this get a progress bar on a terminal

COMMAND = "features"
HELP = "compute loudness, sharpness, booming and low-frequency energy of a file"


def register(sub) -> None:
    from autohaptics.intensity import features as af
    from autohaptics.intensity.loudness import LOUDNESS_METHODS

    p = sub.add_parser(COMMAND, help=HELP, description=__doc__)
    p.add_argument("input", metavar="AUDIO_OR_VIDEO", help="any media file with an audio stream")
    p.add_argument("-o", "--output", required=True, metavar="OUT.json", help="output file, or '-' for stdout")
    d = af.AudioFeatureParams()
    p.add_argument("--pa-per-unit", type=float, default=d.pa_per_unit, metavar="X",
                   help=f"pascal per digital unit (default {d.pa_per_unit}: 0 dBFS rms = 105 dB SPL)")
    p.add_argument("--field", choices=("free", "diffuse"), default=d.field, help="ISO 532-1 sound field")
    p.add_argument("--step-ms", type=int, choices=af.STEPS_MS, default=20,
                   help="20: frame values only; 2: also loudness on the ISO 2 ms grid")
    p.add_argument("--method", choices=LOUDNESS_METHODS, default=d.loudness_method,
                   help=f"loudness method (default {d.loudness_method}; 'iso' = the standard's filter bank)")
    p.add_argument("--booming", choices=("hatano", "paper"), default=d.booming_variant, help="booming index variant")
    p.add_argument("--low-energy-cutoff", type=float, default=d.low_energy_cutoff_hz, metavar="HZ",
                   help=f"low-frequency energy cutoff, Hz (default {d.low_energy_cutoff_hz})")
    p.add_argument("--frame-loudness", choices=af.FRAME_LOUDNESS, default=d.frame_loudness,
                   help="how a 20 ms loudness value is formed from its ten 2 ms values (default max)")
    p.add_argument("--lfe-gain-db", type=float, default=10.0, help="gain of the LFE channel in the downmix, dB")
    p.add_argument("--allow-truncated", action="store_true",
                   help="accept a damaged file that ends before its declared duration (as generate does)")
    p.add_argument("--progress", action="store_true", help="print progress lines even when stderr is not a terminal")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from autohaptics import media
    from autohaptics.intensity import features as af
    from autohaptics.timebase import ANALYSIS_SAMPLE_RATE, FRAME_S

    params = af.AudioFeatureParams(pa_per_unit=args.pa_per_unit, field=args.field, loudness_method=args.method,
                                   booming_variant=args.booming, low_energy_cutoff_hz=args.low_energy_cutoff,
                                   frame_loudness=args.frame_loudness)
    if args.output != "-":
        check_output(args.output)
    info = media.probe(args.input)
    if not args.allow_truncated:
        media.check_complete(info)  # as generate: a file cut short is refused, not analysed in part
    report = media.AudioReport()
    chunks = media.iter_audio(info.path, info=info, lfe_gain_db=args.lfe_gain_db, report=report)
    show = args.progress or info.duration_s > _LONG_INPUT_S
    with ProgressBar("features", force=args.progress) as bar:
        progress = (lambda s: bar("audio", s / info.duration_s)) if show else None
        feats = af.compute_audio_features(chunks, params=params, progress=progress, step_ms=args.step_ms)
        if show:
            bar("done", 1.0)
    doc = _document(info, params, feats, report, args)
    _write_json(doc, args.output)
    if args.output != "-":
        print(f"wrote {args.output} ({feats.n_frames} frames of {FRAME_S * 1000:.0f} ms, "
              f"{feats.n_samples / ANALYSIS_SAMPLE_RATE:.2f} s of audio)", file=sys.stderr)
    return 0


def _document(info: media.MediaInfo, params: af.AudioFeatureParams, feats: af.AudioFeatures,
              report: media.AudioReport, args: argparse.Namespace) -> dict:
    from autohaptics.intensity import features as af
    from autohaptics.intensity.loudness import STEP_S
    from autohaptics.timebase import ANALYSIS_SAMPLE_RATE, FRAME_S

    doc = {
        "source": info.source_block(),
        "params": dataclasses.asdict(params),
        "decode": {"sample_rate": ANALYSIS_SAMPLE_RATE, "samples": feats.n_samples, "lfe_gain_db": args.lfe_gain_db,
                   "main_channels": report.main_channels, "lfe_channel": report.lfe_channel,
                   "downmix_weights": report.downmix_weights,
                   "nonfinite_samples_repaired": report.nonfinite_samples, "decode_errors": report.decode_errors},
        "units": _UNITS,
        "frames": {"step_s": FRAME_S, "n": feats.n_frames, "t_s": _floats(feats.t_s),
                   **{name: _floats(getattr(feats, name)) for name in af.FEATURE_NAMES}},
    }
    if feats.loudness_iso is not None:
        doc["loudness_iso"] = {"step_s": STEP_S, "n": int(feats.loudness_iso.shape[0]),
                               "t_s": _floats(feats.t_iso_s), "loudness": _floats(feats.loudness_iso)}
    return doc


def _floats(x: np.ndarray) -> list[float]:
    import numpy as np

    # Six significant digits: the features' own accuracy is ~1e-3 relative; keeps files small.
    return [float(f"{v:.6g}") for v in np.asarray(x, dtype=np.float64).tolist()]


def _write_json(doc: dict, output: str) -> None:
    if output == "-":
        json.dump(doc, sys.stdout, separators=(",", ":"))
        sys.stdout.write("\n")
        return
    with atomic_output(output, binary=False) as fh:
        json.dump(doc, fh, separators=(",", ":"))
