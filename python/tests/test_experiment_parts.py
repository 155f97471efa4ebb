"""The experiment's parts that need no torch: the real-set reader, the pairing of a network
input with a target rendered with DefaultCrop and Orientation, the PNG reader/writer and the
Delta E maps of the report."""

import json

import numpy as np
import pytest

import day2night
from day2night import png
from day2night.experiment import pairs, realset, unit


def test_png_round_trip_and_other_writers(tmp_path):
    from PIL import Image

    rng = np.random.RandomState(0)
    noise = (rng.rand(37, 53, 3) * 255).astype(np.uint8)
    ramp = np.add.outer(np.arange(40), np.arange(60))[:, :, None] * np.array([1, 2, 3])
    smooth = np.clip(ramp, 0, 255).astype(np.uint8)
    for i, a in enumerate((noise, smooth)):
        p = tmp_path / f"own{i}.png"
        png.write_png(p, a)
        assert (np.asarray(Image.open(p)) == a).all()
        # Pillow's optimizer picks Sub/Up/Average/Paeth filters per row
        q = tmp_path / f"pil{i}.png"
        Image.fromarray(a).save(q, optimize=True)
        assert (png.read_png(q) == a).all()
    grey = smooth[:, :, 0]
    Image.fromarray(grey).save(tmp_path / "g.png")
    assert (png.read_png(tmp_path / "g.png") == np.repeat(grey[:, :, None], 3, 2)).all()
    (tmp_path / "bad.png").write_bytes(b"not a png")
    with pytest.raises(png.PngError, match="bad.png: not a PNG"):
        png.read_png(tmp_path / "bad.png")


def test_png_reads_day2night_render(tmp_path, cli, day_dng):
    out = tmp_path / "t.png"
    cli("render", day_dng, "-o", out)
    from PIL import Image

    assert (png.read_png(out) == np.asarray(Image.open(out).convert("RGB"))).all()


def test_delta_e_map_of_8_bit_images_agrees_with_scikit_image_and_day2night():
    """The report's maps: uint8 sRGB images through ``delta_e2000_map`` as display sRGB (what
    ``unit.score_unit`` writes), then ``unit.heat``."""
    from skimage.color import deltaE_ciede2000, rgb2lab

    rng = np.random.RandomState(1)
    a = (rng.rand(40, 30, 3) * 255).astype(np.uint8)
    b = np.clip(a.astype(int) + rng.randint(-25, 25, a.shape), 0, 255).astype(np.uint8)
    m = day2night.delta_e2000_map(a / 255.0, b / 255.0, pred_linear=False, target_linear=False)
    assert m.shape == (40, 30)
    # scikit-image converts with the 7-digit sRGB matrix and the tabulated D65 white, the
    # library with IEC 61966-2-1's 4-digit matrix and the white of x 0.3127, y 0.3290
    # (docs/isp.md): 0.0096 apart at most on these pixels
    assert np.abs(m - deltaE_ciede2000(rgb2lab(a), rgb2lab(b))).max() < 0.02
    mean = day2night.delta_e2000(a / 255.0, b / 255.0, pred_linear=False, target_linear=False)
    assert m.mean() == pytest.approx(mean, rel=1e-12)
    # the map in the report's colour scale (test_report_page.py): 0 and past the top
    assert unit.heat(np.array([[0.0, 5.0, 99.0]]))[0, [0, 2]].tolist() == [[68, 1, 84],
                                                                         [253, 231, 37]]


@pytest.mark.parametrize("orientation", [1, 3, 6, 8])
def test_network_input_is_cut_and_turned_like_a_default_render(orientation):
    """A target rendered with the ISP's defaults (DefaultCrop, Orientation: what real-pairs
    writes) and an active-area render cut and turned by ``align`` are the same pixels."""
    from conftest import FIXTURES

    day = day2night.read_dng(str(FIXTURES / "day.dng"))
    meta = {k: v for k, v in day.meta.items() if v is not None}
    meta["orientation"] = orientation
    r = day2night.Raw.from_array(day.data, meta, name="o")
    full = day2night.render(r, crop=False, orient=False)
    shown = day2night.render(r)
    assert full.shape != shown.shape
    x, y = pairs.align(full, shown, r.meta)
    assert x.shape == y.shape
    assert np.array_equal(x, y)


def test_quarter_turned_target_is_turned_back():
    x = np.zeros((4, 6, 3), np.float32)
    y = np.arange(6 * 4 * 3).reshape(6, 4, 3).astype(np.uint8)
    ax, ay = pairs.align(x, y, {})
    assert ay.shape == x.shape and np.array_equal(ay, np.rot90(y))
    assert pairs.align(x, np.zeros((5, 5, 3), np.uint8), {}) is None


def write_set(root, scenes, status="ok"):
    lines = []
    for s in scenes:
        outs = []
        for kind, rel in (("clean_raw", f"real/clean_raw/{s}.dng"),
                          ("noisy_raw", f"real/noisy_raw/{s}_iso1600.dng"),
                          ("target", f"real/target/{s}.png")):
            p = root / rel
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(b"x")
            outs.append({"kind": kind, "path": rel, "bytes": 1, "sha256": "0"})
        lines.append(json.dumps({"scene": s, "kind": "real", "status": status, "outputs": outs,
                                 "error": "frames disagree"}))
    (root / "manifest.jsonl").write_text("\n".join(lines) + "\n")


def test_real_set_reader(tmp_path):
    write_set(tmp_path, ["b", "a"])
    got = realset.read_real(tmp_path)
    assert [s.id for s in got] == ["a", "b"]
    assert got[0].noisy == {1600: tmp_path / "real/noisy_raw/a_iso1600.dng"}
    # a torn last line (an interrupted real-pairs run) is dropped
    with open(tmp_path / "manifest.jsonl", "a") as f:
        f.write('{"scene": "c", "ki')
    assert [s.id for s in realset.read_real(tmp_path)] == ["a", "b"]
    with pytest.raises(realset.RealSetError, match="scene b: no ISO 3200 input .*it has 1600"):
        realset.read_real(tmp_path, isos=(1600, 3200))
    (tmp_path / "real/target/b.png").unlink()
    with pytest.raises(realset.RealSetError, match="scene b: .*b.png is listed .* missing"):
        realset.read_real(tmp_path)


def test_real_set_errors(tmp_path):
    with pytest.raises(realset.RealSetError, match="does not exist"):
        realset.read_real(tmp_path / "nope")
    with pytest.raises(realset.RealSetError, match="manifest.jsonl: cannot read.*real-pairs"):
        realset.read_real(tmp_path)
    write_set(tmp_path, ["a"], status="failed")
    with pytest.raises(realset.RealSetError, match="scene a failed in real-pairs: frames disagree"):
        realset.read_real(tmp_path)
