"""The supplementary's burst-denoising row (issue 41, part 6; experiment/burst.py): each
scene's ISO 1600 / 3200 burst averaged by ``day2night.merge`` (the merge real-pairs makes its
clean raw with), rendered by the run's target ISP, scored like every row; left out, with the
reason, on a real set of one frame per ISO or without the captures. No torch needed: the
experiment runs with ``--rows burst`` alone. Needs the CLI (D2N_BIN) for the stand-in set."""

import dataclasses
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import experiment_mini as mini
from conftest import FIXTURES

import day2night
from day2night.experiment import burst, pairs, prepare, rows
from day2night.experiment.config import ExperimentConfig, ExperimentError, resolve
from day2night.train.scores import score


@pytest.fixture(scope="module")
def stand_in(tmp_path_factory, cli):
    """Stand-in captures (3 frames per ISO, both layouts), their real sets, and a real set
    of one frame per noisy ISO (the second and third high-ISO frames removed)."""
    root = tmp_path_factory.mktemp("burst")
    day = mini.day_dir(root / "days", FIXTURES / "day.dng")
    release, simple = mini.bursts(cli, root / "captures", FIXTURES / "day.dng")
    one = root / "one_per_iso"
    shutil.copytree(release, one)
    for p in one.glob("*/RAW_0_00[13]*"):
        if not p.name.endswith("_0000.dng"):
            p.unlink()
    sets = {"release": root / "real", "simple": root / "real_simple", "one": root / "real_one"}
    cli("real-pairs", release, "-o", sets["release"])
    cli("real-pairs", simple, "-o", sets["simple"])
    cli("real-pairs", one, "-o", sets["one"])
    return {"root": root, "day": day, "captures": {"release": release, "simple": simple,
                                                   "one": one}, "real": sets}


def config(s, real="release", captures="release", task="noisy", **kw):
    c = ExperimentConfig(day=str(s["day"]), real=str(s["real"][real]),
                         output=str(s["root"] / "unused"), task=task,
                         captures=str(s["captures"][captures]) if captures else None, **kw)
    return resolve(c)


def inputs_of(c):
    return prepare.read_inputs(c.day, c.real, ["noisy"])


def test_the_row_is_in_the_default_rows_of_the_noisy_task_only(stand_in):
    c, _ = config(stand_in)
    assert c.rows[-1] == "burst"
    assert rows.BY_ID["burst"].label == "Burst denoising (mean of the high-ISO frames)"
    c2, _ = config(stand_in, task="clean")
    assert "burst" not in c2.rows
    with pytest.raises(ValueError, match="--rows burst: .* noisy task only; this run has "
                                         "--task clean"):
        config(stand_in, task="clean", rows=("burst",))
    both, _ = config(stand_in, task="both", rows=("ours", "burst"))
    work = rows.work(["clean", "noisy"], rows.select(list(both.rows)), [])
    assert [(t, r.id) for t, r, _, _ in work] == [("clean", "ours"), ("noisy", "ours"),
                                                  ("noisy", "burst")]


def test_merge_is_real_pairs_merge(stand_in):
    """day2night.merge of the ISO 50 burst is real-pairs' clean raw, sample for sample."""
    scene = stand_in["captures"]["release"] / "scene00"
    frames = sorted(scene.glob("RAW_0_000050_*.dng"))
    merged, report = day2night.merge([str(p) for p in frames])
    clean = day2night.read_dng(str(stand_in["real"]["release"] / "real" / "clean_raw" /
                                   "scene00.dng"))
    assert np.array_equal(np.asarray(merged.data), np.asarray(clean.data))
    for k in ("black_level", "white_level", "as_shot_neutral", "noise_profile"):
        assert merged.meta[k] == clean.meta[k], k
    assert report["frames"] == 3 and report["exact"] is True
    # the mean of the frames, normalized by the levels; a site saturated in any frame white
    f = [day2night.read_dng(str(p)) for p in frames]

    def norm(r):
        black = np.mean(r.meta["black_level"])
        return (np.asarray(r.data, np.float64) - black) / (r.meta["white_level"] - black)

    saturated = np.any([np.asarray(r.data) >= r.meta["white_level"] for r in f], axis=0)
    assert report["saturated_sites"] == saturated.sum() > 0
    mean = np.mean([norm(r) for r in f], axis=0)
    assert np.allclose(norm(merged)[~saturated], mean[~saturated], rtol=0, atol=1e-12)
    assert np.all(norm(merged)[saturated] == 1)
    with pytest.raises(ValueError, match="at least 2 frames"):
        day2night.merge([str(frames[0])])


def test_burst_scores_in_the_units_format_deterministic_and_resumable(stand_in, tmp_path):
    c, isps = config(stand_in)
    inp = inputs_of(c)
    kept, gone = burst.burst_rows(c, inp)
    assert [r.id for r in kept][-1] == "burst" and gone == []
    logs = []
    burst.run_unit(tmp_path, c, inp, isps, log=logs.append)
    path = tmp_path / "units" / "noisy" / "burst" / "all" / "scores.json"
    first = path.read_bytes()
    s = json.loads(first)
    assert {k: s[k] for k in ("task", "row", "fold", "seed", "history", "initial")} == {
        "task": "noisy", "row": "burst", "fold": "all", "seed": None, "history": [],
        "initial": {}}
    scenes = sorted(inp.scenes)
    assert s["test_scenes"] == scenes
    assert [(i["scene"], i["input"]) for i in s["images"]] == [
        (sid, iso) for sid in scenes for iso in ("1600", "3200")]
    assert s["frames"] == {sid: {"1600": 3, "3200": 3} for sid in scenes}
    assert any("averaging the 3 ISO 1600 and 3 ISO 3200 frames" in m for m in logs)
    from day2night.experiment.runfolder import read_scores
    read_scores(tmp_path, path, "noisy", "burst", "all", ["1600", "3200"], scenes)
    # resumable: skipped when done; deterministic: the same bytes again
    burst.run_unit(tmp_path, c, inp, isps, log=logs.append)
    assert "done (scores.json), skipped" in logs[-1] and path.read_bytes() == first
    path.unlink()
    burst.run_unit(tmp_path, c, inp, isps, log=logs.append)
    assert path.read_bytes() == first


def test_a_score_is_the_burst_mean_rendered_and_beats_the_single_frame(stand_in):
    """Independently: the mean of the ISO 1600 frames rendered by the run's ISP (day2night's:
    the active area rendered, cut to the DefaultCrop as the pairing cuts an input) against
    the real-pairs target; and averaging 3 frames scores above the first frame alone."""
    c, isps = config(stand_in)
    inp = inputs_of(c)
    scene = inp.scenes["scene01"]
    bursts = burst.scene_bursts(c.captures, scene, scene.frames)
    target = pairs.real_target(scene, c.targets, isps["scene01"])
    recs = {iso: rec for iso, rec, _, _ in burst.score_scene(bursts, target, c.targets)}
    merged, _ = day2night.merge([str(p) for p in bursts[1600]])
    rgb = day2night.render(merged, demosaic="mhc", crop=False, orient=False, opcodes="ignore")
    from day2night.train.targets import srgb8
    top, left, h, w = merged.meta["default_crop"]
    pred = srgb8(rgb)[top:top + h, left:left + w]
    from day2night.png import read_png
    y = read_png(scene.target)
    assert recs[1600]["psnr"] == score(pred, y)["psnr"]
    single = day2night.read_dng(str(bursts[1600][0]))
    one = srgb8(day2night.render(single, demosaic="mhc", crop=False, orient=False,
                                 opcodes="ignore"))[top:top + h, left:left + w]
    assert recs[1600]["psnr"] > score(one, y)["psnr"] + 1.0


def test_the_release_isp_scores_on_the_release_grid(stand_in, tmp_path):
    c, isps = config(stand_in, targets="release")
    inp = inputs_of(c)
    scene = inp.scenes["scene02"]
    bursts = burst.scene_bursts(c.captures, scene, scene.frames)
    target = pairs.real_target(scene, "release", isps["scene02"])
    got = list(burst.score_scene(bursts, target, "release"))
    merged, _ = day2night.merge([str(p) for p in bursts[3200]])
    pred = pairs.release_render(merged, None)
    assert np.array_equal(got[1][2], pred)
    assert got[1][1]["psnr"] == score(pred, target[0])["psnr"]


def test_the_simple_layout_gives_the_same_scores(stand_in, tmp_path):
    scores = []
    for layout in ("release", "simple"):
        c, isps = config(stand_in, real=layout, captures=layout)
        burst.run_unit(tmp_path / layout, c, inputs_of(c), isps, log=lambda m: None)
        s = json.loads((tmp_path / layout / "units/noisy/burst/all/scores.json").read_text())
        scores.append(s["images"])
    assert scores[0] == scores[1]


def test_left_out_on_one_frame_per_iso_and_without_captures(stand_in):
    c, _ = config(stand_in, real="one", captures="one")
    kept, gone = burst.burst_rows(c, inputs_of(c))
    assert "burst" not in [r.id for r in kept]
    assert gone == [{"task": "noisy", "row": "burst", "why": (
        "the real set holds 1 frame(s) at ISO 1600 for scene scene00 (the authors' processed "
        "tree holds one per ISO): the burst row averages whole bursts")}]
    c, _ = config(stand_in, captures=None)
    kept, gone = burst.burst_rows(c, inputs_of(c))
    assert "burst" not in [r.id for r in kept]
    assert "--captures SCENES" in gone[0]["why"]
    c, _ = config(stand_in, task="noisy", rows=("ours",))
    assert burst.burst_rows(c, inputs_of(c))[1] == []


def test_captures_of_another_set_are_an_error(stand_in, tmp_path):
    c, _ = config(stand_in)
    inp = inputs_of(c)

    def captures(name, edit):
        other = tmp_path / name
        shutil.copytree(stand_in["captures"]["release"], other)
        edit(other)
        return dataclasses.replace(c, captures=str(other))

    fewer = captures("fewer", lambda o: (o / "scene03" / "RAW_0_003200_0002.dng").unlink())
    with pytest.raises(ExperimentError, match=r"scene scene03 .*: 2 ISO 3200 frame\(s\), the "
                                              r"real set's manifest counts 3"):
        burst.burst_rows(fewer, inp)
    swapped = captures("swapped", lambda o: shutil.copy(
        o / "scene00" / "RAW_0_001600_0000.dng", o / "scene04" / "RAW_0_001600_0000.dng"))
    with pytest.raises(ExperimentError, match="scene scene04 .*RAW_0_001600_0000.dng is not "
                                              "the file real-pairs read"):
        burst.burst_rows(swapped, inp)
    nowhere = dataclasses.replace(c, captures=str(tmp_path / "nowhere"))
    with pytest.raises(ExperimentError, match="no folder 'scene00' of scene scene00"):
        burst.burst_rows(nowhere, inp)


def run(args, cwd=None):
    return subprocess.run([sys.executable, "-m", "day2night.experiment", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))


def test_the_command_writes_the_row_into_the_table_without_torch_or_training(stand_in,
                                                                              tmp_path):
    s = stand_in
    out = tmp_path / "run"
    args = ["--day", s["day"], "--real", s["real"]["release"], "-o", out, "--task", "noisy",
            "--rows", "burst", "--captures", s["captures"]["release"]]
    r = run(args)
    assert r.returncode == 0, r.stderr
    t = json.loads((out / "table.json").read_text())
    assert [x["row"] for x in t["rows"]] == ["burst"] and t["left_out"] == []
    assert json.loads((out / "left_out.json").read_text()) == []
    md = (out / "table.md").read_text()
    assert "| Burst denoising (mean of the high-ISO frames) |" in md
    assert "34.91 / 0.8021 / 31.39 / 0.6526" in md
    assert not (out / "units" / "noisy" / "burst" / "all" / "model").exists()
    # left out: the table says why
    out2 = tmp_path / "run_one"
    r = run(["--day", s["day"], "--real", s["real"]["one"], "-o", out2, "--task", "noisy",
             "--rows", "burst"])
    assert r.returncode == 0, r.stderr
    gone = json.loads((out2 / "left_out.json").read_text())
    assert [g["row"] for g in gone] == ["burst"]
    t = json.loads((out2 / "table.json").read_text())
    assert t["rows"] == [] and t["left_out"] == gone
    assert "Left out: burst (noisy task): the real set holds 1 frame(s)" in \
        (out2 / "table.md").read_text()
    assert "row burst (noisy task) left out: the real set holds 1" in r.stderr


def test_left_out_on_the_authors_processed_tree(cli, tmp_path):
    """The release's night_real/ tree (one DNG per ISO): the row is left out, --captures or
    not, and the reason names the frame count."""
    from test_experiment_protocol import processed_tree

    days, tree = processed_tree(cli, tmp_path)
    real = tmp_path / "real"
    cli("real-pairs", tree, "-o", real, "-q")
    for captures in (None, str(tree)):
        c, _ = resolve(ExperimentConfig(day=str(days), real=str(real), output=str(tmp_path / "o"),
                                        task="noisy", captures=captures))
        kept, gone = burst.burst_rows(c, inputs_of(c))
        assert "burst" not in [r.id for r in kept]
        assert gone == [{"task": "noisy", "row": "burst", "why": (
            "the real set holds 1 frame(s) at ISO 1600 for scene 000 (the authors' processed "
            "tree holds one per ISO): the burst row averages whole bursts")}]
