"""Saliency fusion over the 14 triangles (ALGORITHM.md section 3), checked against hand geometry.

Actuators: A1 (1/3, 0), A2 (2/3, 0), A3 (0, 1/2), A4 (1/4, 1/2), A5 (1/2, 1/2), A6 (3/4, 1/2),
A7 (1, 1/2), A8 (1/3, 1), A9 (2/3, 1). Pixel (row i, column j) of an h x w map has its centre at
((j + 0.5) / w, (i + 0.5) / h).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from autohaptics import fusion
from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATOR_IDS

IDX = {a: i for i, a in enumerate(ACTUATOR_IDS)}


def onehot(*actuators: str) -> np.ndarray:
    v = np.zeros(9)
    for a in actuators:
        v[IDX[a]] = 1.0
    return v


# ---------------------------------------------------------------- triangles
def test_triangle_areas_match_the_geometry():
    """Triangles with a 1/3 base on the top or bottom edge (T1, T4, T7, T8, T11, T14) cover 1/12
    of the frame: (1/2)(1/3)(1/2); the others have a 1/4 base on y = 1/2 and height 1/2: 1/16."""
    tri = fusion.triangle_index_map(600, 600)
    assert tri.min() == 0 and tri.max() == 13  # every pixel belongs to a triangle
    share = np.bincount(tri.ravel(), minlength=14) / tri.size
    expected = np.array([1 / 12, 1 / 16, 1 / 16, 1 / 12, 1 / 16, 1 / 16, 1 / 12] * 2)
    np.testing.assert_allclose(share, expected, atol=2e-3)


@pytest.mark.parametrize("xy, triangle", [
    ((0.05, 0.05), 1),    # near C00: T1 (C00, A1, A3)
    ((0.5, 0.1), 4),      # below the A1-A2 edge: T4 (A1, A5, A2)
    ((0.95, 0.05), 7),    # T7 (A2, A7, C10)
    ((0.62, 0.55), 12),   # T12 (A9, A5, A6)
    ((0.95, 0.95), 14),   # T14 (A9, A7, C11)
    ((0.3, 0.7), 10),     # T10 (A8, A4, A5)
])
def test_triangle_of_a_point(xy, triangle):
    h, w = 200, 200
    tri = fusion.triangle_index_map(h, w)
    assert tri[int(xy[1] * h), int(xy[0] * w)] + 1 == triangle


@pytest.mark.parametrize("h, w", [(1, 1), (1, 17), (17, 1), (16, 16), (91, 170)])
def test_triangle_map_covers_any_size(h, w):
    tri = fusion.triangle_index_map(h, w)
    assert tri.shape == (h, w) and tri.min() >= 0 and tri.max() <= 13


@pytest.mark.parametrize("h, w", [(1, 1), (2, 3), (9, 17), (27, 48), (72, 128), (90, 160), (144, 256), (203, 97)])
def test_triangle_map_is_each_pixel_centres_first_triangle(h, w):
    """The map, tested around each triangle's bounding box only, is the rule itself applied to every
    pixel centre of the frame: the first triangle whose barycentric coordinates are all >= -1e-12."""
    px, py = (np.arange(w) + 0.5)[None, :] / w, (np.arange(h) + 0.5)[:, None] / h
    want = np.full((h, w), -1)
    for i, ((x1, y1), (x2, y2), (x3, y3)) in enumerate(fusion.triangles.TRIANGLE_XY):
        det = (y2 - y3) * (x1 - x3) + (x3 - x2) * (y1 - y3)
        l1 = ((y2 - y3) * (px - x3) + (x3 - x2) * (py - y3)) / det
        l2 = ((y3 - y1) * (px - x3) + (x1 - x3) * (py - y3)) / det
        want[(l1 >= -1e-12) & (l2 >= -1e-12) & (1.0 - l1 - l2 >= -1e-12) & (want < 0)] = i
    np.testing.assert_array_equal(fusion.triangle_index_map(h, w), want)


# ---------------------------------------------------------------- weights of one triangle
def test_weights_of_a_corner_centroid():
    """Centroid on the corner C00 of T1 (C00, A1, A3): the corner has no actuator; distances to
    A1 = 1/3 and to A3 = 1/2, alpha = 3 and 2, w = 3/5 and 2/5."""
    w = fusion.triangle_weights((0.0, 0.0), 0)
    np.testing.assert_allclose(w, 0.6 * onehot("A1") + 0.4 * onehot("A3"), rtol=1e-12)


@pytest.mark.parametrize("actuator, triangle", [("A6", 4), ("A6", 5), ("A6", 11), ("A6", 12), ("A1", 0),
                                                ("A5", 10), ("A7", 13)])
def test_centroid_on_a_vertex_gives_that_vertex_one(actuator, triangle):
    xy = fusion.TRIANGLE_XY[triangle][list(fusion.TRIANGLE_ACTUATORS[triangle]).index(IDX[actuator])]
    with np.errstate(all="raise"):
        w = fusion.triangle_weights(tuple(xy), triangle)
    np.testing.assert_array_equal(w, onehot(actuator))


# ---------------------------------------------------------------- whole frames
def test_salient_dot_exactly_at_a6_gives_a6_only():
    """A one-pixel shape whose centre is A6: 10 columns -> (7 + 0.5) / 10 = 0.75; 9 rows ->
    (4 + 0.5) / 9 = 0.5. The pixel lies on the edge of T5, T6, T12 and T13 and belongs to T5;
    its centroid is the vertex A6, which takes weight 1."""
    shape = np.zeros((9, 10), bool)
    shape[4, 7] = True
    np.testing.assert_array_equal(fusion.actuator_weights(shape=shape), onehot("A6"))


def test_salient_blob_centred_on_a6_is_dominated_by_a6():
    """A 7 x 7 blob centred on A6 (pixel (45, 127) of 91 x 170) is split among the four
    triangles around A6; each part's centroid lies within 3 px of A6, so A6 takes almost all of
    each triangle's weight: beta(A6) = 1 and every other actuator stays below 0.05."""
    smap = np.zeros((91, 170), np.float32)
    smap[42:49, 124:131] = 1.0
    beta = fusion.actuator_weights(smap)
    assert beta[IDX["A6"]] == 1.0
    others = np.delete(beta, IDX["A6"])
    assert others.max() < 0.05, beta
    assert set(np.flatnonzero(beta > 0)) <= {IDX[a] for a in ("A2", "A5", "A6", "A7", "A9")}


# Hand computation for a centroid c = (114.5 / 180, 59.5 / 90) = (0.636111, 0.661111) in T12:
#   |c - A9| = |(-0.030556, -0.338889)| = 0.340264  -> alpha 2.938898
#   |c - A5| = |( 0.136111,  0.161111)| = 0.210910  -> alpha 4.741360
#   |c - A6| = |(-0.113889,  0.161111)| = 0.197300  -> alpha 5.068412
#   sum 12.748670: w(A9) = 0.230526, w(A5) = 0.371910, w(A6) = 0.397564
#   beta = w / max(w): A9 0.579846, A5 0.935472, A6 1
T12_BETA = {"A5": 0.935472, "A6": 1.0, "A9": 0.579846}


def _t12_expected() -> np.ndarray:
    v = np.zeros(9)
    for a, b in T12_BETA.items():
        v[IDX[a]] = b
    return v


def test_centroid_inside_t12_weights_by_inverse_distance():
    w = fusion.triangle_weights((114.5 / 180, 59.5 / 90), 11)
    np.testing.assert_allclose(w[[IDX["A9"], IDX["A5"], IDX["A6"]]], [0.230526, 0.371910, 0.397564], atol=2e-6)
    assert w.sum() == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("via", ["shape", "saliency map"])
def test_blob_inside_t12_gives_only_a5_a6_a9(via):
    """A 7 x 7 blob centred on pixel (59, 114) of a 90 x 180 frame lies wholly inside T12; its
    centroid is that pixel's centre, so beta is the hand computation above."""
    region = np.zeros((90, 180), bool)
    region[56:63, 111:118] = True
    assert set(np.unique(fusion.triangle_index_map(90, 180)[region])) == {11}
    if via == "shape":
        beta = fusion.actuator_weights(shape=region)
    else:
        beta = fusion.actuator_weights(region.astype(np.float32))
    np.testing.assert_allclose(beta, _t12_expected(), atol=2e-6)


@pytest.mark.parametrize("empty", [
    np.zeros((90, 160), np.float32),
    np.full((90, 160), np.nan, np.float32),
    np.zeros((1, 1), np.float32),
])
def test_no_salient_region_gives_a5_only(empty):
    with np.errstate(all="raise"):
        beta = fusion.actuator_weights(empty)
    np.testing.assert_array_equal(beta, onehot("A5"))


def test_empty_shape_gives_a5_only():
    np.testing.assert_array_equal(fusion.actuator_weights(shape=np.zeros((9, 17), bool)), onehot("A5"))
    np.testing.assert_array_equal(fusion.fallback_weights(), onehot("A5"))


def test_mass_variant_discounts_a_speck():
    """A large region on the left (T2, T3, T9, T10 ...) and a 2 x 2 speck in T6 (A2, A6, A7):
    "paper" counts the speck's triangle like any other, "mass" by its 4 pixels out of ~2800."""
    shape = np.zeros((90, 180), bool)
    shape[10:80, 10:50] = True
    shape[40:42, 150:152] = True
    tri = fusion.triangle_index_map(90, 180)
    assert set(np.unique(tri[40:42, 150:152])) == {5}
    paper = fusion.actuator_weights(shape=shape, params=fusion.FusionParams(variant="paper"))
    mass = fusion.actuator_weights(shape=shape, params=fusion.FusionParams(variant="mass"))
    speck_acts = [IDX["A2"], IDX["A6"], IDX["A7"]]  # only the speck's triangle reaches them
    assert paper[speck_acts].sum() > 0.3
    assert mass[speck_acts].sum() < 0.01
    assert paper.max() == mass.max() == 1.0
    # the left actuators lead in both
    left = [IDX[a] for a in ("A1", "A3", "A4", "A8")]
    assert mass[left].max() == 1.0 and paper[left].max() == 1.0


def test_mass_equals_paper_for_one_triangle():
    shape = np.zeros((90, 180), bool)
    shape[56:63, 111:118] = True  # inside T12 only
    paper = fusion.actuator_weights(shape=shape)
    mass = fusion.actuator_weights(shape=shape, params=fusion.FusionParams(variant="mass"))
    np.testing.assert_allclose(mass, paper, rtol=1e-12)


# ---------------------------------------------------------------- binarisation
def test_salient_shape_removes_specks_and_keeps_regions():
    smap = np.zeros((90, 160), np.float32)
    smap[30:50, 20:50] = 1.0   # 600 px region
    smap[70, 120] = 1.0        # one-pixel speck
    smap[10:14, 130:134] = 0.9  # 16 px < 0.002 * 14400 = 28.8 px: a speck too
    shape = fusion.salient_shape(smap)
    assert shape[30:50, 20:50].all()
    assert not shape[70, 120] and not shape[10:14, 130:134].any()
    assert shape.sum() == 600


def test_salient_shape_threshold_is_relative_to_the_map():
    """mean + 1.5 std of a map holding one bright region: only the region passes, not the
    mid-level background (0.35 > min_level)."""
    smap = np.full((90, 160), 0.35, np.float32)
    smap[20:60, 100:150] = 1.0
    shape = fusion.salient_shape(smap)
    assert shape.sum() == 40 * 50 and shape[20:60, 100:150].all()


def test_fusion_params_are_checked():
    with pytest.raises(ParameterError, match="variant"):
        fusion.FusionParams(variant="speck")
    with pytest.raises(ParameterError, match="min_level"):
        fusion.FusionParams(min_level=1.5)
    with pytest.raises(ParameterError, match="min_speck_area"):
        fusion.FusionParams(min_speck_area=1.0)
    with pytest.raises(ParameterError, match="2-D"):
        fusion.salient_shape(np.zeros((3, 4, 3)))
    with pytest.raises(ParameterError, match="saliency map or a salient shape"):
        fusion.actuator_weights()


def test_hand_numbers_are_consistent():
    """The literal numbers above, re-derived (guards against a typo in the hand computation)."""
    c = (114.5 / 180, 59.5 / 90)
    alpha = [1 / math.dist(c, p) for p in ((2 / 3, 1.0), (0.5, 0.5), (0.75, 0.5))]
    w = [a / sum(alpha) for a in alpha]
    np.testing.assert_allclose([x / max(w) for x in w], [T12_BETA["A9"], T12_BETA["A5"], T12_BETA["A6"]],
                               atol=2e-6)


@pytest.mark.parametrize("variant", fusion.VARIANTS)
def test_frame_weights_are_the_triangle_rule_summed(variant):
    """actuator_weights (every triangle at once) gives exactly the recipe done one triangle at a
    time: triangle_weights at each triangle's salient centroid (times its salient share for
    "mass"), summed, over the strongest; also with centroids on vertices (one-pixel shapes)."""
    rng = np.random.default_rng(5)
    params = fusion.FusionParams(variant=variant)
    shapes = [rng.random((36, 64)) < p for p in (0.02, 0.2, 0.6)]
    dot = np.zeros((9, 10), bool)
    dot[4, 7] = True  # its centre is A6
    for shape in shapes + [dot]:
        h, w = shape.shape
        tri = fusion.triangle_index_map(h, w)
        total = shape.sum()
        expected = np.zeros(9)
        for t in range(14):
            ys, xs = np.nonzero(shape & (tri == t))
            if ys.size:
                wi = fusion.triangle_weights((((xs + 0.5) / w).sum() / ys.size, ((ys + 0.5) / h).sum() / ys.size), t)
                expected += wi * (ys.size / total if variant == "mass" else 1.0)
        np.testing.assert_allclose(fusion.actuator_weights(shape=shape, params=params), expected / expected.max(),
                                   rtol=1e-12)
