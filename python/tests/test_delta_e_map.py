"""``day2night.delta_e2000_map``: the per-pixel CIEDE2000 behind ``delta_e2000``'s mean (the
report's Delta E maps), checked against the mean, against Sharma, Wu and Dalal (2005)'s test
pairs, and for the input handling ``delta_e2000`` has."""

import numpy as np
import pytest

import day2night

# Linear sRGB -> XYZ as src/metrics/deltae.rs converts (IEC 61966-2-1's 4-digit matrix, the
# D65 white from x 0.3127, y 0.3290): written out here, as tests do not use src/color.
M = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
WHITE = np.array([0.3127 / 0.3290, 1.0, (1 - 0.3127 - 0.3290) / 0.3290])

# Some of the 34 pairs of Sharma, Wu and Dalal (2005), Table 1 (pair number: L1 a1 b1 L2 a2 b2
# dE00); src/metrics/deltae.rs tests all 34 on Lab. Pairs 10 and 14 are left out here: they
# sit exactly on the hue-mean discontinuity (|h1' - h2'| = 180), which the float32 reading of
# the RGB moves them across.
SHARMA = {
    1: [50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425],
    4: [50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000],
    7: [50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669],
    9: [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792],
    13: [50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045],
    17: [50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492],
    19: [50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030],
    25: [60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644],
    31: [90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441],
    34: [2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082],
}


def lab_to_linear(lab):
    """Linear sRGB (unclipped) of a CIELAB colour, the inverse of the library's conversion."""
    L, a, b = lab
    fy = (L + 16) / 116
    f = np.array([fy + a / 500, fy, fy - b / 200])
    t = np.where(f**3 > 216 / 24389, f**3, (116 * f - 16) / (24389 / 27))
    return np.linalg.solve(M, t * WHITE)


def images(seed, h=40, w=30):
    rng = np.random.RandomState(seed)
    a = rng.rand(h, w, 3)
    b = np.clip(a + rng.uniform(-0.15, 0.15, a.shape), 0, 1)
    return a, b


@pytest.mark.parametrize("pred_linear, target_linear",
                         [(True, True), (False, False), (True, False), (False, True)])
def test_the_mean_of_the_map_is_delta_e2000(pred_linear, target_linear):
    a, b = images(0)
    m = day2night.delta_e2000_map(a, b, pred_linear=pred_linear, target_linear=target_linear)
    assert m.shape == (40, 30) and m.dtype == np.float64
    mean = day2night.delta_e2000(a, b, pred_linear=pred_linear, target_linear=target_linear)
    # the same per-pixel values: only the order of the sums differs
    assert m.mean() == pytest.approx(mean, rel=1e-12)
    assert (m >= 0).all()
    assert (day2night.delta_e2000_map(a, a) == 0).all()


def test_the_switches_default_to_linear_like_delta_e2000():
    a, b = images(1)
    assert (day2night.delta_e2000_map(a, b) == day2night.delta_e2000_map(
        a, b, pred_linear=True, target_linear=True)).all()
    assert not np.allclose(day2night.delta_e2000_map(a, b),
                           day2night.delta_e2000_map(a, b, pred_linear=False))


@pytest.mark.parametrize("pair", SHARMA)
def test_sharma_wu_dalal_pairs_through_the_map(pair):
    r = SHARMA[pair]
    pred = lab_to_linear(r[0:3]).reshape(1, 1, 3)
    target = lab_to_linear(r[3:6]).reshape(1, 1, 3)
    # the table's 4 decimals, plus the float32 reading of the linear RGB
    assert day2night.delta_e2000_map(pred, target)[0, 0] == pytest.approx(r[6], abs=1e-4)
    assert day2night.delta_e2000_map(target, pred)[0, 0] == pytest.approx(r[6], abs=1e-4)


def test_pixels_are_where_they_were():
    """Row-major (H, W): a pixel's value is the value of that pixel alone."""
    a, b = images(2, 5, 7)
    m = day2night.delta_e2000_map(a, b, pred_linear=False, target_linear=False)
    for i, j in [(0, 0), (0, 6), (4, 0), (3, 5)]:
        one = day2night.delta_e2000_map(a[i:i + 1, j:j + 1], b[i:i + 1, j:j + 1],
                                        pred_linear=False, target_linear=False)
        assert one[0, 0] == m[i, j]


def test_input_handling_is_delta_e2000s():
    a, b = images(3, 6, 4)
    for dtype in (np.float16, np.float32, np.float64):
        a16, b16 = a.astype(np.float16), b.astype(np.float16)
        m = day2night.delta_e2000_map(a16.astype(dtype), b16.astype(dtype))
        assert (m == day2night.delta_e2000_map(a16, b16)).all()
    with pytest.raises(ValueError, match="pred"):
        day2night.delta_e2000_map((a * 255).astype(np.uint8), b)
    with pytest.raises(ValueError, match="target"):
        day2night.delta_e2000_map(a, b[..., :2])
    with pytest.raises(ValueError, match="sizes differ"):
        day2night.delta_e2000_map(a, b[:5])
