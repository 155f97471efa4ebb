"""The paper's experiment in miniature, the whole way (issue 31, "Done when"): tripod night
bursts of day tiles the training set never sees -> ``day2night real-pairs`` (the authors'
burst layout and the simple one) -> folds -> mixes -> training (UNet width 4, 3 epochs, CPU)
-> scoring -> table. A rerun with the same seed gives the same table.json; a run killed
during training resumes to the same table.json; bad input is a clear error with nothing
written. Needs torch (``pip install day2night[train]``) and the CLI (D2N_BIN)."""

import json
import os
import pathlib
import shutil
import signal
import stat
import subprocess
import sys

import numpy as np
import pytest

from conftest import need_torch

need_torch(module=True)  # skips (or fails) the module the trainer's tests' way

import experiment_mini as mini  # noqa: E402
from conftest import FIXTURES, cli_path, require_tool  # noqa: E402
from report_browser import browser_checks, markdown_visible  # noqa: E402

from day2night.experiment import report  # noqa: E402
from day2night.png import read_png  # noqa: E402

EPOCHS = 3
WIDTH = 4
SMALL = ["--rows", "ours", "supervised", "--task", "both"]


def env():
    e = dict(os.environ)
    # one torch thread: fast on a shared 2-core machine, and the same sums every run
    e.setdefault("OMP_NUM_THREADS", "1")
    return e


@pytest.fixture(scope="session")
def mini_set(tmp_path_factory, cli):
    root = tmp_path_factory.mktemp("mini")
    day = mini.day_dir(root / "days", FIXTURES / "day.dng")
    release, simple = mini.bursts(cli, root / "captures", FIXTURES / "day.dng")
    real, real_simple = root / "real", root / "real_simple"
    cli("real-pairs", release, "-o", real)
    cli("real-pairs", simple, "-o", real_simple)
    return {"root": root, "day": day, "real": real, "real_simple": real_simple,
            "release": release, "simple": simple}


def records(real):
    lines = (pathlib.Path(real) / "manifest.jsonl").read_text().splitlines()
    recs = [json.loads(line) for line in lines if line.strip()]
    return {r["scene"]: r for r in recs}


def test_both_layouts_give_the_same_real_pairs(mini_set):
    a, b = records(mini_set["real"]), records(mini_set["real_simple"])
    assert sorted(a) == [f"scene{i:02d}" for i in range(len(mini.SCENE_TILES))]
    assert sorted(a) == sorted(b)
    for sid in a:
        assert a[sid]["status"] == "ok" and a[sid]["kind"] == "real"
        ha = {o["kind"] + o["path"].rsplit("/", 1)[-1]: o["sha256"] for o in a[sid]["outputs"]}
        hb = {o["kind"] + o["path"].rsplit("/", 1)[-1]: o["sha256"] for o in b[sid]["outputs"]}
        for k in ha:
            if k.startswith(("clean_raw", "noisy_raw", "target")):
                assert ha[k] == hb.get(k), f"{sid}: {k} differs between the two layouts"


@pytest.fixture(scope="session")
def full_run(mini_set):
    out = mini_set["root"] / "run_full"
    r = mini.run_experiment(out, mini_set["day"], mini_set["real"], "--epochs", EPOCHS,
                            "--width", WIDTH, "--seed", 3, env=env())
    return out, r


def test_chain_writes_every_row_of_both_tables(full_run, mini_set):
    out, r = full_run
    assert "SMOKE RUN: network width 4 < 32" in r.stderr
    t = json.loads((out / "table.json").read_text())
    assert t["smoke"] is True
    labels = [(x["task"], x["label"]) for x in t["rows"]]
    want = ["Untrained (the initial weights)", "Day", "Day dimmed", "Global relight", "Ours",
            "Ours 95 % + Real 5 %",
            "Ours 90 % + Real 10 %", "Supervised (k-fold)", "Ours, fresh synthesis"]
    assert labels == [("clean", w) for w in want] + [("noisy", w) for w in want]
    md = (out / "table.md").read_text()
    assert "Smoke run" in md and "Table 1" in md and "Table 2" in md
    assert ("Differs from the paper's protocol: UNet width 4 (paper: 32); 3 epochs (paper: 500); "
            "6 real scenes (paper: 105); 4 day images (paper: 70).") in md
    scenes = sorted(records(mini_set["real"]))
    for row in t["rows"]:
        keys = ["clean"] if row["task"] == "clean" else ["1600", "3200"]
        tested = []
        for u in row["units"]:
            tested += u["test_scenes"]
            assert sorted({i["input"] for i in u["images"]}) == sorted(keys)
            assert len(u["images"]) == len(u["test_scenes"]) * len(keys)
            assert len(u["history"]) == (0 if row["kind"] == "untrained" else EPOCHS)
        # synthetic rows test every scene once; fold rows cover every scene across folds
        assert sorted(tested) == scenes
        for k in keys:
            per_unit = [np.mean([i["psnr"] for i in u["images"] if i["input"] == k])
                        for u in row["units"]]
            assert row["mean"][k]["psnr"] == pytest.approx(np.mean(per_unit), rel=1e-12)


def test_folds_are_disjoint_covering_and_mixes_exact(full_run):
    out, _ = full_run
    f = json.loads((out / "folds.json").read_text())
    tests = [s for sp in f["splits"] for s in sp["test"]]
    assert sorted(tests) == f["scenes"] and len(set(tests)) == len(tests)
    for sp in f["splits"]:
        assert not set(sp["train"]) & set(sp["val"])
        assert not (set(sp["train"]) | set(sp["val"])) & set(sp["test"])
    mixes = json.loads((out / "mixes.json").read_text())
    for row, pct in (("mix5", 5), ("mix10", 10), ("supervised", 100)):
        for sp, slots in zip(f["splits"], mixes[row]):
            n = len(sp["train"])
            assert len(slots) == n
            assert sum(s["kind"] == "real" for s in slots) == round(pct * n / 100)
            assert {s["id"] for s in slots if s["kind"] == "real"} <= set(sp["train"])


def test_training_loss_falls(full_run):
    out, _ = full_run
    t = json.loads((out / "table.json").read_text())
    for row in t["rows"]:
        if row["kind"] == "untrained":
            continue
        for u in row["units"]:
            h = u["history"]
            assert h[-1]["loss"] < h[0]["loss"], (row["task"], row["row"], u["fold"], h)


def test_scores_equal_scikit_image_and_day2night_eval(full_run):
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    out, _ = full_run
    t = json.loads((out / "table.json").read_text())
    checked = 0
    for row in t["rows"]:
        for u in row["units"]:
            for i in u["images"]:
                stem = f"{i['scene']}_{i['input']}"
                pred_png = out / "img" / row["task"] / row["row"] / f"{stem}_pred.png"
                if not pred_png.is_file():
                    continue
                target_png = out / "img" / row["task"] / "scenes" / f"{stem}_target.png"
                pred, target = read_png(pred_png), read_png(target_png)
                p = peak_signal_noise_ratio(target, pred, data_range=255)
                s = structural_similarity(target, pred, channel_axis=-1, data_range=255)
                assert i["psnr"] == pytest.approx(p, rel=1e-6)
                assert i["ssim"] == pytest.approx(s, rel=1e-6, abs=1e-9)
                r = subprocess.run([cli_path(), "eval", pred_png, target_png, "--json"],
                                   capture_output=True, text=True, check=True)
                e = json.loads(r.stdout)
                assert i["psnr"] == pytest.approx(e["psnr"], rel=1e-9)
                assert i["ssim"] == pytest.approx(e["ssim"], rel=1e-9)
                assert i["delta_e"] == pytest.approx(e["delta_e_2000"], rel=1e-9)
                checked += 1
    assert checked >= 8


def test_one_seed_keeps_the_run_folder_layout(full_run):
    out, _ = full_run
    assert "seeds" not in json.loads((out / "config.json").read_text())
    assert not (out / "seeds").exists()
    for task in ("clean", "noisy"):
        units = sorted(p.name for p in (out / "units" / task).iterdir())
        assert units == sorted(["untrained", "day", "dimmed", "global", "ours", "mix5", "mix10",
                                "supervised", "fresh"])
        # the scores and the options record of the unit (records.py), no model/
        assert sorted(p.name for p in (out / "units" / task / "untrained" / "all").iterdir()) \
            == ["options.json", "scores.json"]
        s = json.loads((out / "units" / task / "ours" / "all" / "scores.json").read_text())
        assert sorted(s) == ["fold", "history", "images", "initial", "row", "task",
                             "test_scenes", "train_pairs", "val_pairs"]
    t = json.loads((out / "table.json").read_text())
    assert t["label"] == "smoke" and t["seeds"] == [3] and t["compare_to"] == "day"
    assert [r["kind"] for r in t["rows"]] == (["untrained"] + ["trained"] * 8) * 2


def test_seeds_2_gives_intervals_gains_and_comparisons(mini_set):
    out = mini_set["root"] / "run_seeds"
    mini.run_experiment(out, mini_set["day"], mini_set["real"], "--epochs", 2, "--width", WIDTH,
                        "--rows", "day", "ours", "mix5", "--task", "clean", "--seeds", 2,
                        "--seed", 7, env=env())
    t = json.loads((out / "table.json").read_text(), parse_constant=pytest.fail)
    assert t["seeds"] == [7, 8] and t["compare_to"] == "day"
    assert json.loads((out / "config.json").read_text())["seeds"] == 2
    assert [r["row"] for r in t["rows"]] == ["untrained", "day", "ours", "mix5"]
    for r in t["rows"]:
        assert [u["seed"] for u in r["units"]] == [7] * (len(r["units"]) // 2) + \
            [8] * (len(r["units"]) // 2)
        for m in ("psnr", "ssim", "delta_e"):
            s = r["scores"]["clean"][m]
            assert s["seeds"] == [7, 8] and s["n_scenes"] == 6 and len(s["seed_means"]) == 2
            assert s["ci_low"] <= s["mean"] <= s["ci_high"] and s["seed_sd"] >= 0
        assert (r["gain"] is None) == (r["row"] == "untrained")
    comps = t["comparisons"]
    assert {(c["row"], c["metric"]) for c in comps} == {
        (r, m) for r in ("untrained", "ours", "mix5") for m in ("psnr", "ssim", "delta_e")}
    assert all(c["verdict"] in ("better", "worse", "not distinguishable") for c in comps)
    # the extra seed's units live apart; the first seed's where a one-seed run puts them
    assert (out / "units" / "clean" / "ours" / "all" / "scores.json").is_file()
    extra = json.loads((out / "seeds" / "8" / "units" / "clean" / "mix5" / "1" /
                        "scores.json").read_text())
    assert extra["seed"] == 8
    assert (out / "seeds" / "8" / "units" / "clean" / "untrained" / "all" / "scores.json").is_file()
    md = (out / "table.md").read_text()
    assert "Training seeds: 7, 8" in md and "### Comparisons against Day (clean task)" in md
    # rerun: every unit of both seeds is done, and the table is the same
    r = mini.run_experiment(out, mini_set["day"], mini_set["real"], "--epochs", 2, "--width",
                            WIDTH, "--rows", "day", "ours", "mix5", "--task", "clean",
                            "--seeds", 2, "--seed", 7, env=env())
    assert r.stderr.count("done (scores.json), skipped") == 12
    assert json.loads((out / "table.json").read_text()) == t
    err = mini.run_experiment(out, mini_set["day"], mini_set["real"], "--epochs", 2,
                              "--width", WIDTH, "--rows", "day", "ours", "mix5", "--task",
                              "clean", "--seed", 7, env=env(), check=False).stderr
    assert "seeds = 2, not 1" in err


def test_report_page_shows_test_scenes(full_run):
    out, _ = full_run
    page = (out / "index.html").read_text()
    srcs = [s.split('"')[0] for s in page.split('src="')[1:]]
    assert len(srcs) >= 16 * 4  # every row of both tasks: input, prediction, target, Delta E
    for s in srcs:
        assert (out / s).is_file(), s
    assert not list(out.rglob("*.tmp"))


def test_report_page_of_the_run_in_headless_chromium(full_run):
    """The real run's page (python/tests/test_experiment_report.py tests it on a made-up
    table): HTML tables, no markdown, every image loads, --show 3 shows 3 scenes per row."""
    chromium = require_tool("chromium", "chromium")
    out, r = full_run
    got = browser_checks(chromium, out / "index.html")
    t = json.loads((out / "table.json").read_text())
    tasks = {x["task"] for x in t["rows"]}
    assert got["tables"].count("scores") == len(tasks)
    assert markdown_visible(got["text"]) == []
    assert got["broken"] == []
    # --show's default: 3 scenes, one per fold, shown by every row that writes images
    shown = report.scenes_to_show(t["folds"], 3)[0]
    assert len(shown) == 3
    assert all(set(f["test"]) & set(shown) for f in t["folds"])
    page = (out / "index.html").read_text()
    for x in t["rows"]:
        if x.get("kind") == "burst":
            continue
        for sid in shown:
            for k in (["clean"] if x["task"] == "clean" else ["1600", "3200"]):
                assert f'src="img/{x["task"]}/{x["row"]}/{sid}_{k}_pred.png"' in page
    assert got["images"] >= 4 * len(shown) * len(t["rows"])
    assert "--show 3: showing" not in r.stderr  # 6 scenes: no "showing fewer" line


def test_odd_scene_name_and_the_modes_of_a_run_under_umask_022(mini_set, cli):
    """A scene named ``a#b?c%zz`` (real-pairs takes the folder's name) and a run made under
    umask 022: every file and folder of RUN/ is 0644 / 0755 (index.html, table.*, img/,
    tb/, the models, the data store, log.txt), and in chromium the page's images of that
    scene load and every link of its contents reaches a heading."""
    chromium = require_tool("chromium", "chromium")
    root = mini_set["root"] / "odd"
    captures, real, out = root / "captures", root / "real", root / "run"
    shutil.copytree(mini_set["release"], captures)
    (captures / "scene00").rename(captures / "a#b?c%zz")
    old = os.umask(0o022)
    try:
        cli("real-pairs", captures, "-o", real)
        mini.run_experiment(out, mini_set["day"], real, "--epochs", 1, "--width", WIDTH,
                            "--rows", "ours", "--task", "clean", "--show", 6, env=env())
    finally:
        os.umask(old)
    found = {p: stat.S_IMODE(p.stat().st_mode) for p in out.rglob("*") if not p.is_symlink()}
    assert {p.name for p in found} >= {"index.html", "table.md", "table.json", "log.txt",
                                       "img", "units", "best.pt", "scores.json"}
    wrong = {str(p.relative_to(out)): oct(m) for p, m in found.items()
             if m != (0o755 if p.is_dir() else 0o644)}
    assert wrong == {}
    page = (out / "index.html").read_text()
    assert 'src="img/clean/ours/a%23b%3Fc%25zz_clean_pred.png"' in page
    got = browser_checks(chromium, out / "index.html")
    assert got["broken"] == [] and got["images"] == 4 * 6 * 2
    assert len(got["toc"]) >= 5 and got["unresolved"] == []


@pytest.fixture(scope="session")
def small_run(mini_set):
    out = mini_set["root"] / "run_small"
    mini.run_experiment(out, mini_set["day"], mini_set["real"], "--epochs", EPOCHS,
                        "--width", WIDTH, *SMALL, env=env())
    return out


def test_same_seed_rerun_gives_the_same_table(small_run, mini_set):
    again = mini_set["root"] / "run_small_again"
    mini.run_experiment(again, mini_set["day"], mini_set["real"], "--epochs", EPOCHS,
                        "--width", WIDTH, *SMALL, env=env())
    assert (again / "table.json").read_bytes() == (small_run / "table.json").read_bytes()
    assert (again / "table.md").read_bytes() == (small_run / "table.md").read_bytes()


def test_killed_run_resumes_to_the_same_table(small_run, mini_set):
    out = mini_set["root"] / "run_killed"
    args = ["day2night.experiment", "--day", str(mini_set["day"]),
            "--real", str(mini_set["real"]), "-o", str(out), "--epochs", str(EPOCHS),
            "--width", str(WIDTH), *SMALL]
    cmd = [sys.executable, "-m", *args]
    # the 3rd unit (clean, supervised, fold 1) SIGKILLs itself at step 0 of epoch 1 (the
    # on_step callback kill_at.py gives the 3rd trainer.train call): always inside the unit,
    # after its first epoch is checkpointed, whatever the machine's speed
    kill_at = [sys.executable, str(pathlib.Path(__file__).parent / "kill_at.py"), "3", "1", "0"]
    p = subprocess.run(kill_at + args, capture_output=True, text=True, env=env())
    assert p.returncode == -signal.SIGKILL, p.stderr
    unit3_dir = out / "units" / "clean" / "supervised" / "1"
    assert (unit3_dir / "model" / "last.pt").is_file()
    assert not (unit3_dir / "scores.json").exists()
    assert not (out / "table.json").exists()
    r = subprocess.run(cmd, capture_output=True, text=True, env=env())
    assert r.returncode == 0, r.stderr
    assert ("unit 1/10: task clean, row untrained (Untrained (the initial weights)), fold "
            "all: done (scores.json), skipped") in r.stderr
    assert "unit 2/10: task clean, row ours (Ours), fold all: done (scores.json), skipped" \
        in r.stderr
    assert "unit 3/10: task clean, row supervised (Supervised (k-fold)), fold 0: done" in r.stderr
    unit3 = "unit 4/10: task clean, row supervised (Supervised (k-fold)), fold 1: "
    assert unit3 + f"resuming after epoch 1 of {EPOCHS}" in r.stderr, r.stderr
    assert (out / "table.json").read_bytes() == (small_run / "table.json").read_bytes()


def run_bad(mini_set, name, *args, real=None, day=None):
    out = mini_set["root"] / name
    r = mini.run_experiment(out, day or mini_set["day"], real or mini_set["real"], "--epochs", 1,
                            "--width", WIDTH, *args, env=env(), check=False)
    assert r.returncode == 2, r.stderr
    written = sorted(p.name for p in out.rglob("*")) if out.exists() else []
    assert written == [], f"{name}: files written despite the error: {written}"
    return r.stderr


def test_more_folds_than_scenes_is_a_clear_error(mini_set):
    err = run_bad(mini_set, "bad_folds", "--folds", 7)
    assert "7 folds need at least 7 scenes" in err and "has 6" in err


def test_real_set_too_small_for_the_folds(mini_set):
    small = mini_set["root"] / "real_three"
    small.mkdir()
    (small / "real").symlink_to(mini_set["real"] / "real")
    lines = (mini_set["real"] / "manifest.jsonl").read_text().splitlines()[:3]
    (small / "manifest.jsonl").write_text("\n".join(lines) + "\n")
    err = run_bad(mini_set, "bad_small", "--folds", 2, real=small)
    assert "too small for 2 folds" in err


def test_missing_real_file_names_the_scene(mini_set):
    broken = mini_set["root"] / "real_broken"
    shutil.copytree(mini_set["real"], broken)
    victim = sorted((broken / "real" / "noisy_raw").glob("scene02_iso3200*"))[0]
    victim.unlink()
    err = run_bad(mini_set, "bad_missing", real=broken)
    assert "scene02" in err and "missing" in err


def test_percentage_outside_0_100_is_refused():
    from day2night.experiment import mix

    for bad in (-5, 100.01, 250):
        with pytest.raises(mix.MixError, match="outside 0-100"):
            mix.mix(["a", "b"], ["d.dng"], bad)


def burst_copy(mini_set, name):
    d = mini_set["root"] / name
    shutil.copytree(mini_set["release"], d)
    return d


def test_scene_with_one_frame_is_a_clear_error(mini_set, cli):
    scenes = burst_copy(mini_set, "one_frame")
    bad = scenes / "scene03"
    for f in sorted(bad.glob("RAW_0_000050_*.dng"))[1:]:
        f.unlink()
    out = mini_set["root"] / "one_frame_out"
    r = cli("real-pairs", scenes, "-o", out, check=False)
    assert r.returncode != 0
    assert "scene03" in r.stderr
    assert not (out / "real" / "target" / "scene03.png").exists()


def test_mismatched_frames_are_a_clear_error(mini_set, cli):
    import day2night

    scenes = burst_copy(mini_set, "mismatch")
    # a frame of another size and CFA in scene05's ISO 1600 burst
    raw = day2night.read_dng(str(FIXTURES / "rggb_16bit_le_strips.dng"))
    day2night.write_dng(raw, str(sorted((scenes / "scene05").glob("RAW_0_001600_*.dng"))[0]),
                        overwrite=True)
    out = mini_set["root"] / "mismatch_out"
    r = cli("real-pairs", scenes, "-o", out, check=False)
    assert r.returncode != 0
    assert "scene05" in r.stderr
    assert not (out / "real" / "target" / "scene05.png").exists()


def test_cuda_without_a_gpu_is_a_clear_error(mini_set):
    import torch

    if torch.cuda.is_available():
        pytest.skip("this machine has a CUDA device")
    err = run_bad(mini_set, "bad_cuda", "--device", "cuda")
    assert "--device cuda: torch sees no CUDA device" in err
