"""Issue 18 from Python: DNG opcodes (a GainMap written by the Adobe DNG SDK through dngpy)
are applied by `render` and by synthesized targets, crops included, and `opcodes="ignore"`
leaves them out; metadata that `Raw.from_array` corrects warns, metadata it refuses raises
a ValueError naming the tag."""

import subprocess
import sys
import warnings

import numpy as np
import pytest

import day2night
from conftest import FIXTURES, ROOT

MAKER = ROOT / "tests" / "validators" / "make_gainmap_dng.py"


@pytest.fixture(scope="module")
def gainmap_raw(tmp_path_factory):
    """fixtures/day.dng with a 9x11 GainMap (1 at the centre, 2.6 in the corners) set by the
    Adobe DNG SDK; dngpy is one of the validators the test venv always has."""
    out = tmp_path_factory.mktemp("gainmap") / "day.dng"
    subprocess.run(
        [sys.executable, str(MAKER), "make", str(FIXTURES / "day.dng"), str(out),
         "--rows", "9", "--cols", "11"],
        check=True, capture_output=True,
    )
    return day2night.read_dng(out)


def test_render_applies_the_gainmap_and_ignore_leaves_it_out(gainmap_raw):
    plain = day2night.render(day2night.read_dng(FIXTURES / "day.dng"))
    applied = day2night.render(gainmap_raw)
    ignored = day2night.render(gainmap_raw, opcodes="ignore")
    # The SDK rewrote the file but not its samples: ignoring the map gives the plain render.
    assert np.abs(ignored - plain).max() < 1e-5
    lit = ignored > 0.02
    ratio = applied[lit] / ignored[lit]
    assert 1.2 < np.median(ratio) < 2.0, np.median(ratio)
    with pytest.raises(ValueError, match="opcodes"):
        day2night.render(gainmap_raw, opcodes="sometimes")


def test_targets_apply_opcodes_and_crops_equal_the_frame(gainmap_raw):
    full = day2night.synthesize(gainmap_raw, seed=3, isos=())
    assert full["plan"]["opcodes"] == "apply"
    assert full["plan_report"]["opcodes"]["applied"] == [
        {"list": "OpcodeList2", "name": "GainMap", "id": 9}
    ]
    assert "apply_opcodes" in full["stages"]
    for crop in [(40, 100, 128, 64), (0, 0, 64, 96)]:
        res = day2night.synthesize(gainmap_raw, seed=3, isos=(), crop=crop)
        if res["target_origin"] is None:
            continue
        oy, ox = res["target_origin"]
        _, _, h, w = crop
        assert np.array_equal(res["target"], full["target"][oy:oy + h, ox:ox + w])
    # Only what runs is recorded: no render, no opcode stage.
    raw_only = day2night.synthesize(gainmap_raw, seed=3, isos=(), target=None)
    assert "apply_opcodes" not in raw_only["stages"]
    ignored = day2night.synthesize(gainmap_raw, seed=3, isos=(), opcodes="ignore")
    assert "apply_opcodes" not in ignored["stages"]
    # Synthesis stays on stored values: the clean raw does not depend on the opcodes.
    assert np.array_equal(ignored["clean"], full["clean"])
    assert np.abs(ignored["target"] - full["target"]).max() > 0.1


def test_from_array_warns_about_what_it_corrects_and_names_what_it_refuses():
    raw = day2night.read_dng(FIXTURES / "day.dng")
    meta = dict(raw.meta)
    meta["noise_profile"] = [[0.0, 0.0]]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fixed = day2night.Raw.from_array(raw.data, meta, name="day")
    assert any("NoiseProfile" in str(w.message) for w in caught), [str(w.message) for w in caught]
    assert fixed.meta["noise_profile"] is None
    meta = dict(raw.meta)
    meta["as_shot_neutral"] = [1e6, 1.0, 1.0]
    with pytest.raises(ValueError, match="AsShotNeutral"):
        day2night.Raw.from_array(raw.data, meta, name="day")
