"""Area averaging (:mod:`autohaptics.media.area`): the compiled passes give OpenCV's own bytes, one
axis at a time stays within a grey level of OpenCV's one-pass area average, and without the
kernel OpenCV computes the same."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics import aot
from autohaptics.media import area


def _opencv_two_pass(arr: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """What area_resize computed before the kernel: OpenCV for each axis in turn."""
    w, h = size
    ah, aw = arr.shape
    if w > aw or h > ah:
        return cv2.resize(arr, (w, h), interpolation=cv2.INTER_LINEAR if (w > aw and h > ah) else cv2.INTER_AREA)
    if aw % w == 0 and ah % h == 0:
        return cv2.resize(arr, (w, h), interpolation=cv2.INTER_AREA)
    return cv2.resize(cv2.resize(arr, (w, ah), interpolation=cv2.INTER_AREA), (w, h), interpolation=cv2.INTER_AREA)


@st.composite
def _planes(draw):
    ah, aw = draw(st.integers(1, 300)), draw(st.integers(1, 300))
    seed, blur, step = draw(st.integers(0, 2**31)), draw(st.booleans()), draw(st.sampled_from([1, 1, 2]))
    arr = np.random.default_rng(seed).integers(0, 256, (ah, aw * step), dtype=np.uint8)
    if blur:  # smooth pictures put many sums near a half grey level, where rounding is decided
        arr = cv2.GaussianBlur(arr, (0, 0), 2.0)
    arr = arr[:, ::step]  # a strided view, as a cropped plane is
    return arr, (draw(st.integers(1, aw)), draw(st.integers(1, ah)))


@settings(max_examples=300, deadline=None)
@given(_planes())
def test_area_resize_gives_opencvs_bytes(case):
    arr, size = case
    np.testing.assert_array_equal(area.area_resize(arr, size), _opencv_two_pass(arr, size))


@pytest.mark.parametrize("rows, n", [(240, 90), (427, 160), (480, 64), (7, 3), (1000, 999), (64, 1)])
def test_area_rows_is_opencvs_area_pass(rows, n):
    arr = np.random.default_rng(rows).integers(0, 256, (rows, 37), dtype=np.uint8)
    np.testing.assert_array_equal(area.area_rows(arr, n), cv2.resize(arr, (37, n), interpolation=cv2.INTER_AREA))


def test_without_the_kernel_opencv_computes_the_same(monkeypatch):
    arr = cv2.GaussianBlur(np.random.default_rng(2).integers(0, 256, (240, 427), dtype=np.uint8), (0, 0), 1.5)
    built = area.area_resize(arr, (160, 90))
    monkeypatch.setattr(area, "kernel", lambda: None)
    np.testing.assert_array_equal(area.area_resize(arr, (160, 90)), built)


def test_the_kernel_is_the_extension_built_for_this_processor():
    """The pass runs as machine code built for this processor (named by it), not through OpenCV."""
    assert area.kernel() is not None
    assert area.KERNELS.host_cpu and area.KERNELS.built().__name__ == area.KERNELS.module_name()
    generic = aot.KernelSet(area.KERNELS.prefix, area.KERNELS.source, area.KERNELS.signatures)
    assert generic.module_name() != area.KERNELS.module_name()


@pytest.mark.parametrize("src, size", [((540, 960), (64, 64)), ((1080, 1920), (64, 64)), ((360, 640), (64, 64)),
                                       ((540, 960), (160, 90)), ((90, 160), (64, 64)), ((30, 40), (64, 64))])
def test_area_resize_matches_one_pass_area_averaging(src, size):
    """One axis at a time (fast) gives the one-pass area average within a grey level."""
    rng = np.random.default_rng(3)
    arr = cv2.GaussianBlur(rng.integers(0, 256, src, dtype=np.uint8), (0, 0), 1.5)
    got = area.area_resize(arr, size)
    assert got.shape == (size[1], size[0]) and got.dtype == np.uint8
    one_pass = cv2.resize(arr, size, interpolation=cv2.INTER_AREA if size[0] <= src[1] and size[1] <= src[0]
                          else cv2.INTER_LINEAR)
    assert np.abs(got.astype(int) - one_pass.astype(int)).max() <= 1
