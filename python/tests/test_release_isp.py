"""The release's target ISP from Python (``render_target(raw, isp="release")``,
``render(raw, isp="release")``, ``release_window``): the command line's bytes
(``day2night render --isp release``), the release's own render where the shared data has it,
and the keywords it fixes refused with their names."""

import numpy as np
import pytest

import day2night
from day2night.png import read_png
from day2night.train.targets import release_window, render_target

from conftest import shared_file


@pytest.fixture(scope="module")
def raw(day_dng):
    return day2night.read_dng(day_dng)


def test_python_equals_the_command_line(raw, day_dng, cli, tmp_path):
    out = tmp_path / "r.png"
    cli("render", day_dng, "-o", out, "--isp", "release")
    ours = render_target(raw, isp="release")
    assert ours.dtype == np.uint8
    assert np.array_equal(ours, read_png(out))
    # The release's window: the active area cropped again by ActiveArea (rows 8..520,
    # columns 16..528 of the 512 x 512 active area, clamped).
    assert release_window(raw) == (8, 16, 504, 496)
    assert ours.shape == (504, 496, 3)
    # Its linear sRGB (before gamma): the same window, float32 in [0, 1], brighter where
    # the target is brighter.
    lin = day2night.render(raw, isp="release")
    assert lin.dtype == np.float32 and lin.shape == ours.shape
    assert 0.0 <= lin.min() and lin.max() <= 1.0
    assert np.corrcoef(lin.ravel(), ours.ravel())[0, 1] > 0.9


def test_neutral_and_orientation(raw):
    base = render_target(raw, isp="release")
    warm = render_target(raw, isp="release", neutral=(0.6, 1.0, 0.5))
    assert warm.shape == base.shape and not np.array_equal(warm, base)
    # Orientation 1: orient=False changes nothing; the keywords it implies are accepted.
    same = render_target(raw, isp="release", orient=False, demosaic="menon", tone="release")
    assert np.array_equal(same, base)


@pytest.mark.parametrize("kw,name", [({"demosaic": "bilinear"}, "demosaic"),
                                     ({"tone": "gamma22"}, "tone"),
                                     ({"isp": "libraw"}, "isp")])
def test_contradictions_are_refused(raw, kw, name):
    args = {"isp": "release", **kw}
    with pytest.raises(ValueError, match=name):
        render_target(raw, **args)


def test_render_refuses_what_the_release_fixes(raw):
    with pytest.raises(ValueError, match="crop"):
        day2night.render(raw, isp="release", crop=False)
    with pytest.raises(ValueError, match="opcodes"):
        day2night.render(raw, isp="release", opcodes="warn")
    with pytest.raises(ValueError, match="isp"):
        day2night.render(raw, isp="other")


def test_matches_the_release_render(raw):
    """The release's own render of fixtures/day.dng (shared data)."""
    ref = read_png(shared_file("release-isp/day_release.png"))
    ours = render_target(raw, isp="release")
    assert ours.shape == ref.shape
    off = np.abs(ours.astype(int) - ref.astype(int))
    assert (off <= 1).mean() >= 0.999, off.max()


def without_white_balance(src, dst):
    """``src`` with its AsShotNeutral entry renamed to an unassigned tag (50777): a DNG
    with no white balance, everything else byte for byte."""
    b = bytearray(src.read_bytes())
    assert b[:2] == b"II"
    ifd = int.from_bytes(b[4:8], "little")
    for i in range(int.from_bytes(b[ifd:ifd + 2], "little")):
        e = ifd + 2 + 12 * i
        if int.from_bytes(b[e:e + 2], "little") == 50728:
            b[e:e + 2] = (50777).to_bytes(2, "little")
            break
    else:
        raise AssertionError("no AsShotNeutral in IFD0")
    dst.write_bytes(bytes(b))
    return dst


def test_no_white_balance_is_refused_as_the_default_isp_refuses_it(day_dng, tmp_path):
    raw = day2night.read_dng(without_white_balance(day_dng, tmp_path / "nowb.dng"))
    want = "neither AsShotNeutral nor AsShotWhiteXY"
    with pytest.raises(ValueError, match=want):
        day2night.render(raw)
    with pytest.raises(ValueError, match=want):
        day2night.render(raw, isp="release")
    with pytest.raises(ValueError, match=want):
        render_target(raw, isp="release")
    # A neutral given renders it.
    assert render_target(raw, isp="release", neutral=(0.5, 1.0, 0.6)).shape == (504, 496, 3)


@pytest.mark.parametrize("fill", [0, 65535])
def test_a_constant_render_warns(fill):
    meta = {"cfa_pattern": "RGGB", "black_level": 0, "white_level": 65535,
            "as_shot_neutral": (0.5, 1.0, 0.6), "iso": 100,
            "linearization_table": [fill] * 4096}
    data = (np.arange(48 * 64, dtype=np.uint16).reshape(48, 64) * 7) % 4096
    with pytest.warns(UserWarning):
        raw = day2night.Raw.from_array(data, meta, name="flat")
    for render in (lambda: day2night.render(raw, isp="release"),
                   lambda: render_target(raw, isp="release")):
        with pytest.warns(day2night.RenderConstantWarning, match="the render is constant"):
            out = render()
        assert out.min() == out.max()
    with pytest.warns(day2night.RenderConstantWarning):
        lin = day2night.render(raw, isp="release")
    # All black, or one saturated colour everywhere.
    assert lin.max() == 0.0 if fill == 0 else lin.min() > 0.0
