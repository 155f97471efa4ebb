"""synthesize() and write_outputs() give the command line's numbers and files, byte for byte."""

import filecmp
import json

import numpy as np
import OpenEXR
import pytest

import day2night


def exr_rgb(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        return np.stack([np.asarray(ch[c].pixels) for c in "RGB"], axis=-1)


@pytest.mark.parametrize("mode,extra,cli_extra", [
    ("local", {}, []),
    ("global", {"truncate": True}, ["--truncate"]),
    ("local", {"bulbs": 0, "mask_eval": "exact", "relight_formula": "paper"},
     ["--bulbs", "0", "--mask-eval", "exact", "--relight-formula", "paper"]),
    ("local", {"compat": "release"}, ["--compat", "release"]),
])
def test_synthesize_equals_cli_files(tmp_path, cli, day_dng, mode, extra, cli_extra):
    out_cli = tmp_path / "cli"
    cli("synth", day_dng, "-o", out_cli, "--seed", 7, "--iso", "800,3200", "--mode", mode, *cli_extra)
    raw = day2night.read_dng(day_dng)
    res = day2night.synthesize(raw, seed=7, isos=(800, 3200), mode=mode, **extra)
    clean = day2night.read_dng(out_cli / "day_clean.dng")
    assert np.array_equal(res["clean"], clean.data)
    for iso in (800, 3200):
        noisy = day2night.read_dng(out_cli / f"day_iso{iso}.dng")
        assert np.array_equal(res["noisy"][iso], noisy.data), iso
        assert noisy.meta["iso"] == iso
        got = [list(p) for p in noisy.meta["noise_profile"]]
        assert np.allclose(got, res["noise_profile"][iso], rtol=1e-6)
    # The EXR target holds the half-rounded linear target.
    exr = exr_rgb(out_cli / "day_target.exr")
    assert res["target"].dtype == np.float32
    assert np.array_equal(res["target"].astype(np.float16), exr.astype(np.float16))
    sidecar = json.loads((out_cli / "day.json").read_text())
    assert res["plan"] == sidecar["plan"]
    assert np.allclose(res["neutral"], clean.meta["as_shot_neutral"], rtol=1e-6)
    # write_outputs writes the same files, byte for byte (sidecar included).
    out_py = tmp_path / "py"
    files = day2night.write_outputs(res, raw, out_py)
    assert files == sidecar["outputs"]["files"]
    for name in files:
        assert filecmp.cmp(out_cli / name, out_py / name, shallow=False), name


def test_variant_and_png_outputs_match_cli(tmp_path, cli, day_dng):
    out_cli = tmp_path / "cli"
    cli("synth", day_dng, "-o", out_cli, "--seed", 3, "--variants", 2, "--iso", "1600", "--target", "both")
    raw = day2night.read_dng(day_dng)
    res = day2night.synthesize(raw, seed=3, variant=1, isos=(1600,))
    out_py = tmp_path / "py"
    files = day2night.write_outputs(res, raw, out_py, png=True)
    assert files == ["day_v2_clean.dng", "day_v2_iso1600.dng", "day_v2_target.exr",
                     "day_v2_target.png", "day_v2.json"]
    for name in files:
        assert filecmp.cmp(out_cli / name, out_py / name, shallow=False), name
    # refused without overwrite, written with it
    with pytest.raises(ValueError, match="refusing to overwrite"):
        day2night.write_outputs(res, raw, out_py, png=True)
    day2night.write_outputs(res, raw, out_py, png=True, overwrite=True)


def test_no_target_and_no_iso(tmp_path, cli, day_dng):
    raw = day2night.read_dng(day_dng)
    res = day2night.synthesize(raw, seed=1, isos=(), target=None)
    assert res["target"] is None and res["noisy"] == {}
    assert "render_target" not in res["stages"] and "noise" not in res["stages"]
    out_cli = tmp_path / "cli"
    cli("synth", day_dng, "-o", out_cli, "--seed", 1, "--iso", "none", "--target", "none")
    files = day2night.write_outputs(res, raw, tmp_path / "py")
    assert files == ["day_clean.dng", "day.json"]
    for name in files:
        assert filecmp.cmp(out_cli / name, tmp_path / "py" / name, shallow=False), name


def test_real_camera_file_matches_cli(tmp_path, cli, real_dng):
    out_cli = tmp_path / "cli"
    cli("synth", real_dng, "-o", out_cli, "--seed", 2, "--iso", "1600")
    raw = day2night.read_dng(real_dng)
    res = day2night.synthesize(raw, seed=2, isos=(1600,))
    stem = real_dng.stem
    assert np.array_equal(res["clean"], day2night.read_dng(out_cli / f"{stem}_clean.dng").data)
    assert np.array_equal(res["noisy"][1600], day2night.read_dng(out_cli / f"{stem}_iso1600.dng").data)


PHYSICS = {
    "model": "physics",
    "format": "day2night-physics-noise-model/1",
    "units": "DN of linear values",
    "source": "python test",
    "black": 256.0,
    "white": 4095.0,
    "poisson_max_electrons": 1000.0,
    "isos": [
        {"iso": 400, "k": 0.5, "sigma_read": 2.0, "lambda": 0.0, "gaussian_read": False, "sigma_row": 0.6},
        {"iso": 1600, "k": 2.0, "sigma_read": 5.0, "lambda": -0.05, "gaussian_read": False, "sigma_row": 2.0},
    ],
}


def test_physics_noise_model_matches_cli_and_crops(tmp_path, cli, day_dng):
    model = tmp_path / "physics.json"
    model.write_text(json.dumps(PHYSICS))
    out_cli = tmp_path / "cli"
    cli("synth", day_dng, "-o", out_cli, "--seed", 4, "--iso", "800", "--noise-model", model)
    raw = day2night.read_dng(day_dng)
    res = day2night.synthesize(raw, seed=4, isos=(800,), noise_model=str(model))
    assert res["plan"]["noise"][0]["physics"]["k"] > 0
    noisy = day2night.read_dng(out_cli / "day_iso800.dng").data
    assert np.array_equal(res["noisy"][800], noisy)
    # per-site draws: a crop's physics noise is the frame's
    t, l, _, _ = raw.meta["active_area"]
    crop = day2night.synthesize(raw, seed=4, isos=(800,), noise_model=str(model), crop=(2, 4, 10, 12))
    assert np.array_equal(crop["noisy"][800], noisy[t + 2:t + 12, l + 4:l + 16])
