"""Python's synthesis keywords against the option table (src/synth/options/table.rs):
every option the table gives Python is taken, by the functions the table names, with
errors naming the keyword; an unknown keyword lists the table's names; the keywords and
defaults the functions had before the table are unchanged."""

import inspect
import shutil

import pytest

import day2night
from day2night import _native

TABLE = _native.SYNTH_OPTIONS


def keywords(*scopes):
    return [k for k, e in TABLE.items() if e["python"] in scopes]


@pytest.fixture(scope="module")
def raw(day_dng):
    return day2night.read_dng(day_dng)


@pytest.fixture(scope="module")
def unit(day_dng, tmp_path_factory):
    days = tmp_path_factory.mktemp("days")
    shutil.copy(day_dng, days / "a.dng")
    return day2night.dataset_units(days)[0]


def test_table_is_the_flags(cli):
    help_text = cli("synth", "--help").stdout
    for key, e in TABLE.items():
        assert e["flag"] == "--" + key.replace("_", "-")
        assert e["flag"] + " " in help_text or e["flag"] + "\n" in help_text, key
        if e["default"] is not None:
            assert f"[default: {e['default']}]" in help_text, key


def test_the_old_keywords_are_all_there():
    """The keywords Python took before the table (none dropped, none renamed)."""
    before = {"relight_formula", "bulbs", "lights", "truncate", "covariance", "day_neutral",
              "mask_eval", "compat", "opcodes", "illuminants", "brightness", "noise_model",
              "burst", "motion", "shake_step", "shake_roll", "warp_interp"}
    assert before <= set(keywords("keyword"))
    files_before = {"iso", "mode", "target", "input_exr", "compression", "exr_compression",
                    "exr_zip_level"}
    assert files_before <= set(keywords("keyword", "files", "parameter"))


@pytest.mark.parametrize("key", keywords("keyword"))
def test_every_keyword_is_parsed_by_synthesize(raw, key):
    with pytest.raises((TypeError, ValueError)) as e:
        day2night.synthesize(raw, isos=(1600,), crop=(0, 0, 32, 32), target=None,
                             **{key: object()})
    assert key in str(e.value)
    assert "unknown option" not in str(e.value)


@pytest.mark.parametrize("key", keywords("keyword", "files", "parameter"))
def test_every_keyword_is_parsed_by_write_unit(unit, tmp_path, key):
    with pytest.raises((TypeError, ValueError)) as e:
        day2night.write_unit(unit, tmp_path, **{key: object()})
    assert key in str(e.value)
    assert "unknown option" not in str(e.value)


def test_unknown_keyword_lists_the_table(raw, unit, tmp_path):
    with pytest.raises(ValueError) as e:
        day2night.synthesize(raw, colour=1)
    msg = str(e.value)
    assert "unknown option \"colour\"" in msg
    for key in keywords("keyword"):
        assert key in msg
    for key in keywords("files"):
        assert key not in msg.split("known:")[1]
    with pytest.raises(ValueError) as e:
        day2night.write_unit(unit, tmp_path, colour=1)
    for key in keywords("keyword", "files", "parameter"):
        assert key in str(e.value)


@pytest.mark.parametrize("kwargs,match", [
    ({"bulbs": 300}, r"bulbs: 300 is outside 0\.\.=256"),
    ({"mask_eval": "fast"}, r"mask_eval: .*fast.*separable"),
    ({"relight_formula": "new"}, r"relight_formula: .*new.*release or paper"),
    ({"compat": "paper"}, r"compat: .*paper.*release"),
    ({"dim_range": (0.9, 0.5)}, r"dim_range: LO 0\.9 is above HI 0\.5"),
    ({"bulb_gain": (1, 2, 3)}, r"bulb_gain: 3 values given"),
    ({"ambient_gain": "x"}, r"ambient_gain must be a number"),
    ({"burst": True}, r"burst must be an integer \(got bool\)"),
])
def test_errors_name_keyword_value_and_allowed(raw, kwargs, match):
    with pytest.raises((TypeError, ValueError), match=match):
        day2night.synthesize(raw, isos=(1600,), crop=(0, 0, 32, 32), **kwargs)


def test_new_options_reach_the_plan(raw):
    out = day2night.synthesize(raw, isos=(1600,), crop=(0, 0, 32, 32), target=None,
                               dim_range=(0.3, 0.3), ambient_gain=0.1, bulb_gain="60,60",
                               formula="release")
    assert out["plan"]["dim"]["s"] == pytest.approx(0.3)
    assert out["plan"]["dim"]["range"] == [0.3, 0.3]
    base = day2night.synthesize(raw, isos=(1600,), crop=(0, 0, 32, 32), target=None)
    assert base["plan"]["dim"]["range"] == [0.55, 0.9]


def test_parameters_bind_as_before(raw, day_dng, tmp_path):
    """synthesize's parameters by position or by name, as its signature says."""
    crop = (0, 0, 32, 32)
    a = day2night.synthesize(raw, 3, 0, "local", (1600,), None, crop)
    b = day2night.synthesize(raw, seed=3, variant=0, mode="local", isos=(1600,), target=None,
                             crop=crop)
    assert (a["clean"] == b["clean"]).all()
    assert a["target"] is None and a["crop"] == crop
    with pytest.raises(TypeError, match="multiple values for argument 'seed'"):
        day2night.synthesize(raw, 3, seed=3)
    with pytest.raises(TypeError, match="positional"):
        day2night.synthesize(raw, 3, 0, "local", (1600,), None, crop, 1)
    assert inspect.signature(day2night.synthesize).parameters["seed"].default == 0
    with pytest.raises(TypeError, match="unexpected keyword argument 'colour'"):
        day2night.dataset_units(tmp_path, colour=1)
    with pytest.raises(ValueError, match=r"variants: 0 is outside"):
        day2night.dataset_units(tmp_path, variants=0)
    with pytest.raises(TypeError):
        day2night.dataset_units(tmp_path, None, 2)


def test_noise_gain_scales_the_noise(raw):
    """--noise-gain K: the noise model's S and O times K^2 (its standard deviation times K),
    the clean raw unchanged; K = 1 is the model as calibrated."""
    base = day2night.synthesize(raw, isos=(1600,), crop=(0, 0, 32, 32), target=None)
    one = day2night.synthesize(raw, isos=(1600,), crop=(0, 0, 32, 32), target=None,
                               noise_gain=1)
    two = day2night.synthesize(raw, isos=(1600,), crop=(0, 0, 32, 32), target=None,
                               noise_gain=2)
    assert one["noise_profile"] == base["noise_profile"]
    assert (one["noisy"][1600] == base["noisy"][1600]).all()
    for (s1, o1), (s2, o2) in zip(base["noise_profile"][1600], two["noise_profile"][1600]):
        assert s2 == pytest.approx(4 * s1) and o2 == pytest.approx(4 * o1)
    assert (two["clean"] == base["clean"]).all()
    assert not (two["noisy"][1600] == base["noisy"][1600]).all()
    with pytest.raises(ValueError, match=r"noise_gain: 0 is not > 0"):
        day2night.synthesize(raw, isos=(1600,), crop=(0, 0, 32, 32), noise_gain=0)
