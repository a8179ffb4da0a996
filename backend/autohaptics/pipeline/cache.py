"""The analysis cache: what :func:`~autohaptics.pipeline.derive.derive` needs of a film, stored as
one .npz file, and whether it can serve a set of parameters."""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from autohaptics import __version__
from autohaptics.params import GenerateParams, analysis_key
from autohaptics.pipeline.ticks import VideoAnalysis
from autohaptics.records import params_to_dict
from autohaptics.shots import Boundaries, detect


# Raised when the analysis computes otherwise for the same parameters (a rule changed without a
# parameter of its own): a cache of another revision is analysed again. 1: every frame decoded at
# 29-40 fps (``media.video.REPEAT_MIN_FPS``); caches before it carry none and count as 0. 2: audio
# frames placed on the container's clock without splices at rounded timestamps (``media.audio.AudioClock``).
# 3: 10-bit and wider pictures read through the 8-bit proxies' path (``media.frames``); a master's mono
# tracks read as its mix (``media.tracks.channel_tracks``); HDR pictures read as SDR (``media.hdr``).
# 4: every frame decoded where skipping the non-reference ones leaves gaps (``media.video.SKIP_GAP_MAX``).
# 5: an interlaced frame's proxies read from its top field (``media.frames``); the film's mix picked among
# several audio tracks, not the first (``media.tracks.sound_stream``); AC-3 and E-AC-3 read without the
# stream's dynamic range compression (``media.audio``); proxies at the picture's shown aspect (an
# anamorphic DVD's, ``media.frames``); a 3D film read from its first view (``video.stereo``).
# 6: a transport stream read on its continuous clock, across its wrap and jumps, its pictures found at their
# keyframes' bytes (``media.clock``); a picture decoded at another size than its stream's scaled to it
# (``media.frames``); a sound that changes layout mid-stream downmixed by each layout (``media.audio``).
# 7: repeats told in runs and a pair timed by the picture's mean step, its least span in steps (``airflow.cadence``);
# every frame decoded from 40 fps up where the pictures repeat (``pipeline.picture.decode_mode``).
# 8: a sound that changes sample rate mid-stream resampled from each rate (``media.audio``).
# 9: a transport stream of several programmes read as one programme, its clock its own (``media.programs``).
# 10: a translucent overlay wider than a filled one may be (a watermark) unblended (``media.overlays``).
# 11: a run of repeats longer than a cadence's is a picture held, outside the mean step (``airflow.cadence``).
ANALYSIS_REVISION = 11


@dataclass
class Analysis:
    """The feature cache of one file: what :func:`derive` needs, nothing that depends on thresholds.

    audio : {"loudness" sone, "sharpness" acum, "booming" 1, "low_energy" Pa^2}, each float64
        [shape=(n_frames,)] on the 20 ms grid, n_frames = n_ticks * 5; None without an audio stream.
    shots : the shot boundaries (:func:`autohaptics.shots.detect`), found from ``video`` on first
        use when not given (a cache written before they were stored gets them from its own arrays;
        a plain ``generate`` never needs them, so it never pays for them).
    revision : the :data:`ANALYSIS_REVISION` it was computed under.
    """

    info: dict
    sha256: str
    n_ticks: int
    params: dict
    audio: dict[str, np.ndarray] | None
    video: VideoAnalysis | None = None
    stats: dict = field(default_factory=dict)
    found_shots: Boundaries | None = None
    revision: int = ANALYSIS_REVISION

    @property
    def shots(self) -> Boundaries:
        if self.found_shots is None:
            v = self.video
            self.found_shots = Boundaries.build([]) if v is None else detect(
                cut=v.cut, signature=v.signature, mean_rgb=v.mean_rgb if v.mean_rgb.any() else None,
                frame_mask=v.frame_mask)
        return self.found_shots

    def save(self, path: str | Path) -> None:
        """Write the cache as one .npz file (arrays plus a JSON header)."""
        arrays = {f"audio_{k}": v for k, v in (self.audio or {}).items()}
        if self.video is not None:
            arrays.update({f"video_{k}": v for k, v in self.video.arrays().items()})
        arrays.update({"shots_tick": self.shots.tick, "shots_kind": self.shots.kind, "shots_span": self.shots.span})
        header = {"info": self.info, "sha256": self.sha256, "n_ticks": self.n_ticks, "params": self.params,
                  "stats": self.stats, "has_audio": self.audio is not None, "has_video": self.video is not None,
                  "version": __version__, "revision": self.revision}
        buf = io.BytesIO()
        np.savez(buf, header=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8), **arrays)
        Path(path).write_bytes(buf.getvalue())

    @classmethod
    def load(cls, path: str | Path) -> "Analysis":
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(bytes(z["header"]).decode())
            audio = {k[len("audio_"):]: z[k] for k in z.files if k.startswith("audio_")}
            video = {k[len("video_"):]: z[k] for k in z.files if k.startswith("video_")}
            shots = Boundaries(tick=z["shots_tick"], kind=z["shots_kind"], span=z["shots_span"]) \
                if "shots_tick" in z.files else None
        return cls(info=header["info"], sha256=header["sha256"], n_ticks=int(header["n_ticks"]),
                   params=header["params"], audio=audio if header["has_audio"] else None,
                   video=VideoAnalysis.from_arrays(video) if header.get("has_video") else None,
                   stats=header["stats"], found_shots=shots, revision=int(header.get("revision", 0)))


def reusable(analysis: Analysis, params: GenerateParams | dict) -> bool:
    """True when ``analysis`` was computed with the analysis-time parameters of ``params`` (a
    record or its ``params_to_dict`` form) by this code's analysis (:data:`ANALYSIS_REVISION`):
    deriving from it then equals analysing again."""
    doc = params if isinstance(params, dict) else params_to_dict(params)
    return analysis.revision == ANALYSIS_REVISION and analysis_key(analysis.params) == analysis_key(doc)
