"""Night bursts in Python (issue 25): synthesize(burst=N) and NightPairs(burst=N)."""

import filecmp
import json

import numpy as np
import pytest

import day2night
from day2night import NightPairs

ZERO = {
    "format": "day2night-noise-model/1",
    "units": "normalized",
    "source": "noise-free test camera",
    "isos": [{"iso": 1600, "positions": [[0, 0], [0, 0], [0, 0], [0, 0]]}],
}


@pytest.fixture(scope="module")
def raw(day_dng):
    return day2night.read_dng(day_dng)


def test_frames_are_n_by_h_by_w_and_frame_00_is_the_single_frame(raw):
    one = day2night.synthesize(raw, seed=3, isos=(1600,), target=None)
    assert one["noisy"][1600].ndim == 2
    assert one["transforms"] is None
    b = day2night.synthesize(raw, seed=3, isos=(1600,), target=None, burst=4)
    n = b["noisy"][1600]
    assert n.shape == (4,) + one["noisy"][1600].shape and n.dtype == np.uint16
    assert np.array_equal(n[0], one["noisy"][1600])
    assert np.array_equal(b["clean"], one["clean"])
    assert not np.array_equal(n[1], n[0])
    t = b["transforms"]
    assert len(t) == 4 and t[0]["affine"] == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    assert t == b["plan"]["burst"]["transforms"]
    still = day2night.synthesize(raw, seed=3, isos=(1600,), target=None, burst=4, motion="none")
    assert all(x["affine"] == t[0]["affine"] for x in still["transforms"])
    with pytest.raises(ValueError):
        day2night.synthesize(raw, isos=(1600,), burst=65)
    with pytest.raises(ValueError):
        day2night.synthesize(raw, isos=(1600,), burst=2, motion="tripod")


def test_burst_equals_the_command_line_and_writes_the_same_files(tmp_path, cli, day_dng, raw):
    out_cli = tmp_path / "cli"
    cli("synth", day_dng, "-o", out_cli, "--seed", 5, "--iso", "800", "--burst", 3,
        "--motion", "shake", "--shake-step", "1.5")
    res = day2night.synthesize(raw, seed=5, isos=(800,), burst=3, motion="shake", shake_step=1.5)
    for k in range(3):
        f = day2night.read_dng(out_cli / f"day_iso800_f{k:02d}.dng")
        assert np.array_equal(res["noisy"][800][k], f.data), k
    sidecar = json.loads((out_cli / "day.json").read_text())
    assert res["plan"] == sidecar["plan"]
    out_py = tmp_path / "py"
    files = day2night.write_outputs(res, raw, out_py)
    assert files == sidecar["outputs"]["files"]
    for name in files:
        assert filecmp.cmp(out_cli / name, out_py / name, shallow=False), name


def test_crops_are_windows_of_every_frame(tmp_path, raw):
    model = tmp_path / "zero.json"
    model.write_text(json.dumps(ZERO))
    opts = dict(seed=1, isos=(1600,), target=None, burst=4, shake_step=2.0, shake_roll=0.2,
                noise_model=str(model))
    full = day2night.synthesize(raw, **opts)
    top, left = raw.meta["active_area"][0], raw.meta["active_area"][1]
    for crop in [(0, 0, 40, 50), (100, 202, 77, 91), (440, 430, 72, 82)]:
        c = day2night.synthesize(raw, crop=crop, **opts)
        t, l, h, w = crop
        got = c["noisy"][1600]
        assert got.shape == (4, h, w)
        want = full["noisy"][1600][:, top + t:top + t + h, left + l:left + l + w]
        assert np.array_equal(got, want), crop


def test_night_pairs_burst_items(day_dng, tmp_path):
    d = tmp_path / "days"
    d.mkdir()
    (d / "day.dng").write_bytes(day_dng.read_bytes())
    single = NightPairs(d, crop=64, isos=(1600,), seed=2)
    ds = NightPairs(d, crop=64, isos=(1600,), seed=2, burst=3)
    a, b = single[0], ds[0]
    assert b["noisy"].shape == (3, 4, 32, 32) and b["noisy"].dtype == np.float32
    assert np.array_equal(b["noisy"][0], a["noisy"])
    assert np.array_equal(b["clean"], a["clean"])
    assert b["transforms"].shape == (3, 2, 3) and b["valid"].shape == (3, 4)
    assert np.array_equal(b["transforms"][0], [[1, 0, 0], [0, 1, 0]])
    assert "transforms" not in a
    assert np.array_equal(ds[0]["noisy"], b["noisy"])
