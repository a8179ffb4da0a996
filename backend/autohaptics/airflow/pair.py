"""What one flow pair says about its tick: a cut inside it, no motion at all (static or a fade), or
its motion per fan cell and, where it moves past the floor, how near each cell is.

A pair is a tick's analysed frame and the next decoded frame; the video pass
(:mod:`autohaptics.pipeline.video`) feeds the pairs and stores the results.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from autohaptics.airflow import cuts, depth
from autohaptics.airflow.fans import AirflowParams, cell_motion, grid_means
from autohaptics.airflow.flow import FlowParams, is_fade, is_static, motion_magnitude, motion_score, optical_flow
from autohaptics.imaging import resized
from autohaptics.layout import FAN_COLS, FAN_ROWS


def run_directly(stage: str, fn: Callable, *args, **kwargs):
    """The default ``timer`` of :func:`pair_motion`: calls ``fn`` (``stage`` names it for timing)."""
    return fn(*args, **kwargs)


@dataclass
class PairMotion:
    """cut : a cut inside the pair (no motion sample). static : nothing moved, or only the
    brightness changed. score : mean motion, frame widths/s. cells : [shape=(9, 17)] frame widths/s
    (None for a cut). near : [shape=(9, 17)] nearness 0..1 where depth ran, else None."""

    cut: bool = False
    static: bool = False
    score: float = 0.0
    cells: np.ndarray | None = None
    near: np.ndarray | None = None


@dataclass(frozen=True)
class PairParams:
    """The stage parameters a pair is judged with. floor : frame widths/s below which depth is not
    computed (negative: always). skip : static pairs are skipped (no flow)."""

    flow: FlowParams
    airflow: AirflowParams
    cuts: cuts.CutParams
    depth: depth.DepthParams
    floor: float
    skip: bool


def _brightness_step(gray0: np.ndarray, gray1: np.ndarray, params: AirflowParams) -> bool:
    """Two pictures with detail that differ only by brightness and contrast: a step of a fast fade
    (two frames apart its luma signature can jump like a cut's), not a cut. A pair with a flat
    picture (a cut into or out of black) is not such a step: it stays a cut."""
    return min(float(gray0.std()), float(gray1.std())) >= params.flat_std and is_fade(gray0, gray1, params=params)


def pair_motion(gray0: np.ndarray, gray1: np.ndarray, rgb0: np.ndarray, sig0: np.ndarray | None,
                successor_sig: Callable[[], np.ndarray], dt_s: float, *, params: PairParams,
                depth_backend=None, timer: Callable = run_directly,
                luma_signature: Callable[[np.ndarray], np.ndarray] = cuts.frame_signature) -> PairMotion:
    """Motion (and depth when the motion passes the floor) from one frame pair.

    gray0, gray1 : uint8 [shape=(h, w)] gray proxies; rgb0 : the first frame's RGB proxy;
    sig0 : its cut signature (or None); successor_sig() : the second frame's colour signature,
    read only when the pair moves past the floor; dt_s : the pair's real interval, s.
    timer(stage, fn, *args, **kwargs) runs each stage ("static", "flow", "depth"), e.g. timed.
    luma_signature(gray) : a gray proxy's cut signature (a caller that pairs each frame twice keeps it).
    The same as :func:`pair_verdict`, else :func:`motion_from_flow` of the pair's optical flow.
    """
    verdict = pair_verdict(gray0, gray1, params=params, timer=timer, luma_signature=luma_signature)
    if verdict is not None:
        return verdict
    flow = timer("flow", optical_flow, gray0, gray1, params=params.flow)
    return motion_from_flow(flow, gray0, rgb0, sig0, successor_sig, dt_s, params=params, depth_backend=depth_backend,
                            timer=timer)


def pair_verdict(gray0: np.ndarray, gray1: np.ndarray, *, params: PairParams, timer: Callable = run_directly,
                 luma_signature: Callable[[np.ndarray], np.ndarray] = cuts.frame_signature) -> PairMotion | None:
    """What a pair is without its flow: a cut (luma signatures), a fade's step, or static (nothing
    moved beyond noise, or only the brightness changed); None when its motion needs the flow
    (arguments as :func:`pair_motion`)."""
    if cuts.is_cut(luma_signature(gray0), luma_signature(gray1), params=params.cuts):
        if not _brightness_step(gray0, gray1, params.airflow):
            return PairMotion(cut=True)
        return PairMotion(static=True, cells=np.zeros((FAN_ROWS, FAN_COLS), np.float32))  # a fade's step
    if (params.skip and timer("static", is_static, gray0, gray1, params=params.airflow)) or \
            timer("static", is_fade, gray0, gray1, params=params.airflow):
        return PairMotion(static=True, cells=np.zeros((FAN_ROWS, FAN_COLS), np.float32))
    return None


def motion_from_flow(flow: np.ndarray, gray0: np.ndarray, rgb0: np.ndarray, sig0: np.ndarray | None,
                     successor_sig: Callable[[], np.ndarray], dt_s: float, *, params: PairParams,
                     depth_backend=None, timer: Callable = run_directly) -> PairMotion:
    """A moving pair's motion per cell from its optical flow (``optical_flow(gray0, gray1)``), a cut
    where the colour signatures say so, and depth where the motion passes the floor (arguments
    as :func:`pair_motion`)."""
    mag = motion_magnitude(flow, dt_s=dt_s, width_px=gray0.shape[1])
    score = motion_score(mag)
    if score > params.floor:
        sig1 = successor_sig()
        if sig0 is not None and sig0.shape == sig1.shape and cuts.is_cut(sig0, sig1, params=params.cuts):
            return PairMotion(cut=True)
    result = PairMotion(score=score, cells=cell_motion(mag))
    if score > params.floor:
        near = timer("depth", depth.nearness_map, resized(rgb0, params.depth.proxy_width),
                     params=params.depth, backend=depth_backend, flow=flow, dt_s=dt_s)
        result.near = grid_means(near)
    return result
