"""Typed warnings (docs/warnings.md): every warning the extension raises is the
``day2night.Day2NightWarning`` subclass of its Rust code, with ``code``, ``subject`` and
``message``, as the command line prints ``warning[CODE]: SUBJECT: MESSAGE``."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import day2night
from conftest import FIXTURES

DOCS = Path(__file__).resolve().parents[2] / "docs"


def test_one_exported_subclass_per_code_and_every_code_documented():
    codes = [c for c, _ in day2night.WARNING_CODES]
    assert len(codes) == len(set(codes)) and "noise-extrapolated" in codes
    assert issubclass(day2night.Day2NightWarning, UserWarning)
    doc = (DOCS / "warnings.md").read_text()
    for code in codes:
        cls = day2night.warning_class(code)
        assert issubclass(cls, day2night.Day2NightWarning) and cls.code == code
        assert getattr(day2night, cls.__name__) is cls and cls.__name__ in day2night.__all__
        assert f"| `{code}` |" in doc, code
    assert sorted(re.findall(r"^\| `([a-z-]+)` \|", doc, re.M)) == sorted(codes)
    assert day2night.NoiseExtrapolatedWarning.code == "noise-extrapolated"
    assert day2night.warning_class("not-a-code") is day2night.Day2NightWarning


def test_a_real_synthesis_raises_its_warning_with_the_code():
    raw = day2night.read_dng(FIXTURES / "day.dng")
    with pytest.warns(day2night.NoiseExtrapolatedWarning) as rec:
        day2night.synthesize(raw, seed=3, isos=(25,), target=None)
    got = [w.message for w in rec if issubclass(w.category, day2night.Day2NightWarning)]
    assert [(w.code, w.subject) for w in got] == [("noise-extrapolated", "day.dng")], got
    assert got[0].message.startswith("ISO 25 scaled from the single calibrated ISO 100")
    assert str(got[0]) == f"day.dng: {got[0].message}"
    # Attributed to the caller, not to day2night's own module.
    assert rec[0].filename == __file__
    # One code can be silenced alone.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", day2night.NoiseExtrapolatedWarning)
        day2night.synthesize(raw, seed=3, isos=(25,), target=None)


def test_metadata_defaults_and_corrections_have_their_codes():
    raw = day2night.read_dng(FIXTURES / "day.dng")
    m = {k: raw.meta[k] for k in ("cfa_pattern", "black_level", "white_level")}
    m["calibration_illuminant1"] = 99
    m["color_matrix1"] = np.eye(3)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        day2night.Raw.from_array(raw.data, m, name="bare")
    codes = {w.message.code for w in rec if issubclass(w.category, day2night.Day2NightWarning)}
    assert {"metadata-default", "calibration-illuminant-unknown"} <= codes, codes
    assert all(w.message.subject == "bare.dng" for w in rec), [str(w.message) for w in rec]
