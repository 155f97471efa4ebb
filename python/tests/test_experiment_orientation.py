"""Input and target of a pair on one pixel grid, for each of the 8 Exif orientations (issue 35).

A stand-in scene: a 512 x 384 cut of ``fixtures/day.dng`` (the astronaut photograph: no
symmetry), without a DefaultCrop, whose DNGs carry the orientation. Its clean raw and ISO 1600
input go through ``experiment.pairs.real_pair`` against a target rendered the way real-pairs
renders it (day2night's defaults: the image turned for display), or the way the release
renders its ``clean/`` PNGs (its crop and its own ``fix_orientation``). The input and target
patches must line up: on every textured 64 x 64 patch of the stride-64 grid (but the image's border),
the edges of the input and of the target correlate best at offset (0, 0), and strongly.

Flips and the half turn (2, 3, 4) keep the shape, so a pairing that only looked at shapes
left those targets flipped against an unturned input."""

import types

import numpy as np
import pytest

import day2night
from conftest import FIXTURES
from day2night.experiment import pairs
from day2night.png import write_png
from day2night.train.targets import srgb8

H, W = 384, 512
PATCH = 64
SHIFT = 3


def edges(img):
    """Gradient magnitude of the grey image (float64)."""
    g = np.asarray(img, np.float64).mean(axis=2)
    gy, gx = np.gradient(g)
    return np.hypot(gx, gy)


def correlations(a, b):
    """{(dy, dx): r}: the correlation of ``a``'s centre with ``b``'s window shifted by
    (dy, dx), for shifts within +-SHIFT."""
    m = SHIFT
    core = a[m:-m, m:-m].ravel()
    return {
        (dy, dx): np.corrcoef(core, b[m + dy : b.shape[0] - m + dy,
                                      m + dx : b.shape[1] - m + dx].ravel())[0, 1]
        for dy in range(-m, m + 1)
        for dx in range(-m, m + 1)
    }


def assert_one_grid(x, y):
    """Every textured patch's edges correlate strongly at offset (0, 0), and no shift does
    clearly better; most patches are best at exactly (0, 0). Patches on the image's border
    are left out: there the demosaics (OpenCV's bilinear for the input; MHC or Menon for the
    target) each treat the outermost pixels their own way, which can favour a 1-2 pixel
    shift on a weak edge."""
    assert x.shape == y.shape, (x.shape, y.shape)
    ex, ey = edges(x), edges(np.asarray(y, np.float64) / 255)
    checked = exact = 0
    for top in range(PATCH, x.shape[0] - 2 * PATCH + 1, PATCH):
        for left in range(PATCH, x.shape[1] - 2 * PATCH + 1, PATCH):
            a = ex[top : top + PATCH, left : left + PATCH]
            b = ey[top : top + PATCH, left : left + PATCH]
            if a.std() < 0.01:
                continue  # a flat patch: nothing to line up
            r = correlations(a, b)
            best = max(r, key=r.get)
            assert r[0, 0] > 0.8 and r[0, 0] > r[best] - 0.01, (top, left, best, r[best],
                                                                  r[0, 0])
            checked += 1
            exact += best == (0, 0)
    assert checked >= 15 and exact >= 0.9 * checked, (checked, exact)


def stand_in_raw(orientation):
    day = day2night.read_dng(str(FIXTURES / "day.dng"))
    t, l = day.meta["active_area"][:2]
    data = np.ascontiguousarray(day.data[t + 64 : t + 64 + H, l : l + W])
    meta = {k: v for k, v in day.meta.items() if v is not None}
    meta.update(active_area=None, default_crop=None, orientation=orientation, width=W, height=H)
    return day2night.Raw.from_array(data, meta, name=f"orient{orientation}")


def scene(tmp_path, raw, target):
    clean = tmp_path / "clean.dng"
    noisy = tmp_path / "noisy_iso1600.dng"
    day2night.write_dng(raw, str(clean), overwrite=True)
    day2night.write_dng(raw, str(noisy), overwrite=True)
    png = tmp_path / "target.png"
    write_png(png, target)
    return types.SimpleNamespace(id="s", clean_raw=clean, target=png, noisy={1600: noisy})


@pytest.mark.parametrize("orientation", range(1, 9))
def test_real_pair_of_a_real_pairs_target_is_on_one_grid(tmp_path, orientation):
    raw = stand_in_raw(orientation)
    shown = srgb8(day2night.render(raw))  # the bytes real-pairs writes as the target PNG
    assert shown.shape[:2] == ((H, W) if orientation < 5 else (W, H))
    sc = scene(tmp_path, raw, shown)
    for iso in (None, 1600):
        x, y = pairs.real_pair(sc, iso, targets="day2night", source="day2night")
        assert np.array_equal(y, shown)  # the PNG itself: the clean raw has no opcode lists
        assert_one_grid(x, y)


@pytest.mark.parametrize("orientation", range(1, 9))
def test_real_pair_of_a_release_target_is_on_one_grid(tmp_path, orientation):
    """A stand-in for the release's clean/NNN.png: the active area cropped by the release's
    window and turned by its fix_orientation (2 and 4, 5 and 7 swapped against Exif)."""
    raw = stand_in_raw(orientation)
    meta = dict(raw.meta)
    meta["active_area"] = [0, 0, H, W]
    flat = srgb8(day2night.render(raw, crop=False, orient=False))
    ref = pairs.release_orient(flat, orientation)
    sc = scene(tmp_path, raw, np.ascontiguousarray(ref))
    x, y = pairs.real_pair(sc, 1600, targets="release", source="release")
    assert_one_grid(x, y)
    if orientation in (2, 4, 5, 7):
        # the Exif turn would put the release's target the other way round
        assert not np.array_equal(pairs.orient(flat, orientation), ref)


def test_release_orientation_is_its_fix_orientation():
    """The release's fix_orientation through OpenCV, for each tag value."""
    cv2 = pytest.importorskip("cv2")
    img = np.arange(3 * 5 * 3, dtype=np.uint8).reshape(3, 5, 3)
    ops = {
        1: lambda a: a,
        2: lambda a: cv2.flip(a, 0),
        3: lambda a: cv2.rotate(a, cv2.ROTATE_180),
        4: lambda a: cv2.flip(a, 1),
        5: lambda a: cv2.rotate(cv2.flip(a, 0), cv2.ROTATE_90_COUNTERCLOCKWISE),
        6: lambda a: cv2.rotate(a, cv2.ROTATE_90_CLOCKWISE),
        7: lambda a: cv2.rotate(cv2.flip(a, 0), cv2.ROTATE_90_CLOCKWISE),
        8: lambda a: cv2.rotate(a, cv2.ROTATE_90_COUNTERCLOCKWISE),
    }
    for o, op in ops.items():
        assert np.array_equal(pairs.release_orient(img, o), op(img)), o


def test_release_window_crops_the_active_area_twice():
    """fixtures/day.dng: ActiveArea 8,16,520,528 of a 528 x 520 file; the release keeps rows
    8..511 and columns 16..511 of the 512 x 512 active area (496 x 504, its README)."""
    meta = {"active_area": [8, 16, 520, 528]}
    assert pairs.release_window(meta, 512, 512) == (8, 16, 504, 496)
    assert pairs.release_window({"active_area": [0, 0, 30, 40]}, 30, 40) == (0, 0, 30, 40)
    assert pairs.release_window({}, 30, 40) == (0, 0, 30, 40)


def warp_list(k1):
    """An OpcodeList3 holding one WarpRectilinear (kr = 1, k1, 0, 0; centred), big-endian as
    DNG stores it."""
    import struct

    params = struct.pack(">I6d2d", 1, 1.0, k1, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5)
    return struct.pack(">III", 1, 1, 0x01030000) + struct.pack(">II", 0, len(params)) + params


def test_opcode_lists_are_ignored_on_both_sides(tmp_path):
    """A DNG with a WarpRectilinear (corners moved by about 10 pixels): the network input never
    applies it, so neither does the target: synthetic and real pairs stay on one grid."""
    raw = stand_in_raw(1)
    meta = dict(raw.meta)
    meta["opcode_list3"] = warp_list(0.03)
    warped = day2night.Raw.from_array(raw.data, meta, name="warped")
    day = tmp_path / "warped.dng"
    day2night.write_dng(warped, str(day))
    assert pairs.has_opcodes(day2night.read_dng(str(day)).meta)
    applied = srgb8(day2night.render(warped))
    assert not np.array_equal(applied, srgb8(day2night.render(warped, opcodes="ignore")))
    x, y = pairs.synth_pairs(day, "day", 1, isos=())["clean"]
    assert_one_grid(x, y)
    # real-pairs' PNG applies the lists: the target is rendered again without them
    sc = scene(tmp_path, warped, applied)
    x, y = pairs.real_pair(sc, None, targets="day2night", source="day2night")
    assert np.array_equal(y, srgb8(day2night.render(warped, opcodes="ignore")))
    assert_one_grid(x, y)
    with pytest.raises(AssertionError):
        assert_one_grid(x, applied)  # the warped target is off the input's grid


RELEASE_REFS = ["day", "day_orient3", "day_orient6", "day_orient8", "night_clean",
                "grbg_12bit_packed_be_strips", "rggb_12bit_ljpeg_tiles_deltas"]


@pytest.mark.parametrize("name", RELEASE_REFS)
def test_the_release_geometry_is_the_releases_own_render(name):
    """The authors' own renders (../shared/data/release-isp: its crop, its orientation fix)
    against the network input cut and turned by the release geometry: the whole image's
    edges correlate best at offset (0, 0), and so do nearly all textured patches (Menon
    against bilinear demosaicing moves a few weak-edged patches)."""
    from conftest import SHARED_DATA, shared_file

    from day2night.png import read_png
    from day2night.train.preprocess import network_input

    ref = shared_file(f"release-isp/{name}_release.png")
    dng = SHARED_DATA / "release-isp" / f"{name}.dng"
    raw = day2night.read_dng(str(dng if dng.is_file() else FIXTURES / f"{name}.dng"))
    x, y = pairs.align(network_input(raw), read_png(ref), raw.meta, "release")
    ex, ey = edges(x), edges(np.asarray(y, np.float64) / 255)
    whole = correlations(ex, ey)
    assert max(whole, key=whole.get) == (0, 0) and whole[0, 0] > 0.85, whole[0, 0]
    best = []
    for top in range(0, x.shape[0] - PATCH + 1, PATCH):
        for left in range(0, x.shape[1] - PATCH + 1, PATCH):
            a = ex[top : top + PATCH, left : left + PATCH]
            if a.std() >= 0.01:
                r = correlations(a, ey[top : top + PATCH, left : left + PATCH])
                best.append(max(r, key=r.get))
    assert best.count((0, 0)) >= 2 / 3 * len(best), best


@pytest.mark.parametrize("orientation", range(1, 9))
def test_synthetic_release_targets_are_on_one_grid(tmp_path, orientation):
    """A day image carrying the orientation, synthesized with the release's ISP for its
    target (its crop and its fix_orientation): the input is cut and turned onto it."""
    raw = stand_in_raw(orientation)
    day = tmp_path / "day.dng"
    day2night.write_dng(raw, str(day))
    x, y = pairs.synth_pairs(day, "day", 1, isos=(), targets="release")["clean"]
    assert y.shape[:2] == ((H, W) if orientation < 5 else (W, H))
    assert_one_grid(x, y)


def test_the_release_window_is_the_release_isps():
    """pairs.release_window (numpy, from the metadata: the run-folder checks use it) against
    the window the release ISP itself crops (day2night.train.targets.release_window)."""
    from day2night.train.targets import release_window

    for name in ("day.dng", "grbg_12bit_packed_be_strips.dng",
                 "rggb_12bit_ljpeg_tiles_deltas.dng", "rggb_16bit_le_strips.dng"):
        raw = day2night.read_dng(str(FIXTURES / name))
        t, l, b, r = raw.meta["active_area"]
        assert pairs.release_window(raw.meta, b - t, r - l) == tuple(release_window(raw)), name


@pytest.mark.parametrize("orientation", [1, 2, 6])
def test_a_real_target_of_the_other_isp_is_rendered_again(tmp_path, orientation):
    """--targets release on a real set whose PNGs day2night rendered: the target is the
    release ISP's render of the scene's clean raw, on the input's grid."""
    from day2night.train.targets import render_target

    raw = stand_in_raw(orientation)
    sc = scene(tmp_path, raw, srgb8(day2night.render(raw)))
    x, y = pairs.real_pair(sc, 1600, targets="release", source="day2night")
    clean = day2night.read_dng(str(sc.clean_raw))
    assert np.array_equal(y, render_target(clean, isp="release"))
    assert_one_grid(x, y)
    x, y = pairs.real_pair(sc, None, targets="day2night", source="release")
    assert np.array_equal(y, srgb8(day2night.render(clean, opcodes="ignore")))
    assert_one_grid(x, y)
