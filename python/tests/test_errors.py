"""Errors are Python exceptions with the command line's messages, never a crash."""

import numpy as np
import pytest

import day2night


def test_missing_file_is_oserror(tmp_path, cli):
    missing = tmp_path / "nope.dng"
    with pytest.raises(OSError) as e:
        day2night.read_dng(missing)
    r = cli("info", missing, check=False)
    assert r.returncode == 1
    assert str(e.value) in r.stderr  # the CLI prints "day2night: <same message>"


def test_garbage_file_is_valueerror(tmp_path, cli):
    bad = tmp_path / "bad.dng"
    bad.write_bytes(b"II*\x00" + b"\xff" * 60)
    with pytest.raises(ValueError) as e:
        day2night.read_dng(bad)
    r = cli("info", bad, check=False)
    assert r.returncode == 1
    assert str(e.value) in r.stderr


@pytest.mark.parametrize("kwargs,match", [
    ({"crop": (1, 0, 8, 8)}, "even"),
    ({"crop": (0, 0, 8, 10**7)}, "outside"),
    ({"crop": (0, 0, 0, 8)}, r"crop\[2\] \(height\): 0 is outside 1\.\.=512"),
    ({"isos": (0,)}, r"isos\[0\]: 0 is outside 1\.\.=4000000"),
    ({"mode": "night"}, "mode"),
    ({"target": "exr"}, "linear"),
    ({"mask_eval": "fast"}, "separable"),
    ({"bulbs": 10**6}, r"bulbs: 1000000 is outside 0\.\.=256"),
    ({"colour": 1}, "unknown option"),
    ({"noise_model": "/nonexistent/model.json"}, "model.json"),
])
def test_bad_parameters(day_dng, kwargs, match):
    raw = day2night.read_dng(day_dng)
    exc = OSError if "noise_model" in kwargs else ValueError
    with pytest.raises(exc, match=match):
        day2night.synthesize(raw, **kwargs)


def test_bad_arrays(day_dng):
    a = np.zeros((4, 4, 3), np.float32)
    with pytest.raises(ValueError):
        day2night.psnr(a, np.zeros((4, 5, 3), np.float32))
    with pytest.raises(ValueError, match=r"target must be height x width x 3 \(got shape \(4, 4\)\)"):
        day2night.psnr(a, np.zeros((4, 4), np.float32))
    raw = day2night.read_dng(day_dng)
    res = day2night.synthesize(raw, isos=(1600,))
    res["clean"] = res["clean"][:3]
    with pytest.raises(ValueError):
        day2night.write_outputs(res, raw, "/tmp/never-written-d2n")
