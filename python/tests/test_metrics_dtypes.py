"""The metrics take images of any float dtype (float16, float32, float64) and give the same
values for the same image, equal to ``day2night eval`` on EXR files holding it."""

import json

import numpy as np
import OpenEXR
import pytest

import day2night

DTYPES = [np.float16, np.float32, np.float64]


def pair(h=37, w=29, seed=5):
    """Two related linear images whose values float16 holds exactly (so every dtype holds
    the same image)."""
    rng = np.random.default_rng(seed)
    a = rng.uniform(0.0, 1.0, (h, w, 3))
    b = np.clip(a + rng.normal(0.0, 0.05, a.shape), 0.0, 1.2)
    return a.astype(np.float16), b.astype(np.float16)


def write_exr(path, rgb):
    rgb = np.ascontiguousarray(rgb, dtype=np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    channels = {c: np.ascontiguousarray(rgb[..., i]) for i, c in enumerate("RGB")}
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))


def metrics(a, b, **kw):
    return (day2night.psnr(a, b), day2night.ssim(a, b), day2night.delta_e2000(a, b),
            day2night.ssim(a, b, window="gaussian"))


def test_every_float_dtype_gives_the_same_values():
    a, b = pair()
    ref = metrics(a.astype(np.float32), b.astype(np.float32))
    for da in DTYPES:
        for db in DTYPES:
            assert metrics(a.astype(da), b.astype(db)) == ref, (da, db)
    # Non-contiguous arrays and other float widths are read the same way.
    assert metrics(np.asfortranarray(a.astype(np.float64)), b[::1, ::1].astype(np.float16)) == ref
    if hasattr(np, "longdouble"):
        assert metrics(a.astype(np.longdouble), b) == ref


def test_float64_is_read_as_float32_like_an_exr():
    rng = np.random.default_rng(1)
    a, b = rng.uniform(0, 1, (20, 24, 3)), rng.uniform(0, 1, (20, 24, 3))
    assert metrics(a, b) == metrics(a.astype(np.float32), b.astype(np.float32))


def test_values_equal_the_cli(cli, tmp_path):
    a, b = pair(64, 48)
    write_exr(tmp_path / "a.exr", a)
    write_exr(tmp_path / "b.exr", b)
    r = json.loads(cli("eval", tmp_path / "a.exr", tmp_path / "b.exr", "--json").stdout)
    g = json.loads(cli("eval", tmp_path / "a.exr", tmp_path / "b.exr", "--json",
                       "--ssim-window", "gaussian").stdout)
    for dt in DTYPES:
        x, y = a.astype(dt), b.astype(dt)
        assert day2night.psnr(x, y) == pytest.approx(r["psnr"], rel=1e-12)
        assert day2night.ssim(x, y) == pytest.approx(r["ssim"], rel=1e-12)
        assert day2night.delta_e2000(x, y) == pytest.approx(r["delta_e_2000"], rel=1e-12)
        assert day2night.ssim(x, y, window="gaussian") == pytest.approx(g["ssim"], rel=1e-12)


@pytest.mark.parametrize("bad,match", [
    (np.zeros((4, 4, 3), np.int32), r"pred: dtype int32 is not a float dtype"),
    (np.zeros((4, 4, 3), np.uint16), r"pred: dtype uint16 is not a float dtype"),
    (np.zeros((4, 4, 3), bool), r"pred: dtype bool is not a float dtype"),
    (np.zeros((4, 4, 3), np.complex64), r"pred: dtype complex64 is not a float dtype"),
    (np.zeros((4, 4, 4), np.float64), r"pred must be height x width x 3 \(got shape \(4, 4, 4\)\)"),
    (np.zeros(12, np.float16), r"pred must be height x width x 3 \(got shape \(12,\)\)"),
    ([[[0.0, 0.0, 0.0]]], r"pred must be a numpy float array of height x width x 3 \(got list\)"),
])
def test_non_float_or_misshapen_arrays_are_named(bad, match):
    ok = np.zeros((4, 4, 3), np.float32)
    for f in (day2night.psnr, day2night.ssim, day2night.delta_e2000):
        with pytest.raises(ValueError, match=match):
            f(bad, ok)
