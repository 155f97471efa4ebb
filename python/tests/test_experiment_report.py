"""The experiment's report (issue 41, "A page researchers read"): RUN/index.html built by
day2night.experiment.report from a table.json (format /2, and a format /1 table without the
new fields) with real PNGs written by the scorer's image writer; opened in headless chromium
(report_browser.py) it shows real <table>s, no markdown, and every image loads. Also the
learning curves (small multiples), the choice of the shown scenes (``--show``) and the
TensorBoard event files of RUN/tb read back."""

import copy
import html.parser
import os
import pathlib

import numpy as np
import pytest

from conftest import require_tool
from report_browser import browser_checks, markdown_visible, screenshot

from day2night.experiment import curves, report, report_grid, report_tables, tb
from day2night.experiment.unit import _report_images

SCENES = ["s0", "s1", "s2", "s3", "s4"]
FOLDS = [{"fold": 0, "train": ["s2", "s3"], "val": ["s4"], "test": ["s0", "s1"]},
         {"fold": 1, "train": ["s0", "s4"], "val": ["s1"], "test": ["s2", "s3"]},
         {"fold": 2, "train": ["s0", "s1"], "val": ["s2"], "test": ["s4"]}]
KEYS = {"clean": ["clean"], "noisy": ["1600", "3200"]}


def score(task, row, sid, key):
    """A made-up but deterministic per-scene score."""
    base = {"untrained": 9.0, "day": 26.0, "ours": 27.0, "supervised": 28.0, "burst": 30.0}[row]
    k = SCENES.index(sid) + (0 if key in ("clean", "1600") else 1)
    return {"scene": sid, "input": key, "psnr": base + 0.1 * k, "ssim": base / 40 + 0.01 * k,
            "delta_e": 40.0 / base + 0.01 * k}


def unit(task, row, fold, scenes, seed, epochs=4):
    history = [] if row in ("untrained", "burst") else [
        {"epoch": i, "loss": 0.3 / (i + 1) + 0.01 * (seed or 0), "val_loss": 0.4 / (i + 1.5),
         "val_psnr": 10.0 + 2 * i, "lr": 1e-3} for i in range(epochs)]
    return {"task": task, "row": row, "fold": fold, "seed": seed, "history": history,
            "initial": {} if not history else {"val_loss": 0.45, "val_psnr": 8.0},
            "images": [score(task, row, s, k) for s in scenes for k in KEYS[task]],
            "test_scenes": list(scenes)}


def stats(values):
    m = float(np.mean(values))
    return {"mean": m, "ci_low": m - 0.5, "ci_high": m + 0.5, "n_scenes": len(SCENES),
            "seeds": [0], "seed_means": [m], "seed_sd": None}


def row(task, row_id, label, kind, per_fold=False, paper=None):
    seed = None if kind != "trained" else 0
    units = ([unit(task, row_id, str(f["fold"]), f["test"], seed) for f in FOLDS] if per_fold
             else [unit(task, row_id, "all", SCENES, seed)])
    images = [i for u in units for i in u["images"]]
    scores = {k: {m: stats([i[m] for i in images if i["input"] == k])
                  for m in ("psnr", "ssim", "delta_e")} for k in KEYS[task]}
    mean = {k: {m: v["mean"] for m, v in s.items()} for k, s in scores.items()}
    return {"task": task, "row": row_id, "label": label, "kind": kind, "units": units,
            "mean": mean, "scores": scores, "paper": paper,
            "gain": None if kind == "untrained" else
            {k: {m: {"mean": 1.0, "ci_low": 0.5, "ci_high": 1.5} for m in s}
             for k, s in scores.items()}}


def table():
    """A table.json of format /2 over both tasks (every field of docs/experiment.md)."""
    rows = []
    for task in ("clean", "noisy"):
        paper = ({"clean": {"psnr": 41.16, "ssim": 0.9713, "delta_e": 1.2369}}
                 if task == "clean" else
                 {"1600": {"psnr": 36.10, "ssim": 0.9215}, "3200": {"psnr": 33.55,
                                                                    "ssim": 0.8960}})
        rows += [row(task, "untrained", "Untrained (the initial weights)", "untrained"),
                 row(task, "day", "Day <b>&", "trained", paper=paper),
                 row(task, "ours", "Ours", "trained"),
                 row(task, "supervised", "Supervised (k-fold)", "trained", per_fold=True)]
    rows.append(row("noisy", "burst", "Burst denoising (mean of the high-ISO frames)",
                    "burst"))
    comps = [{"task": "clean", "row": "ours", "reference": "day", "input": "clean",
              "metric": m, "mean": d, "ci_low": d - 0.2, "ci_high": d + 0.2, "n_scenes": 5,
              "seeds": [0], "verdict": v}
             for m, d, v in (("psnr", 1.0, "better"), ("ssim", 0.0, "not distinguishable"),
                             ("delta_e", 0.3, "worse"))]
    return {"format": "day2night-experiment-table/2", "config": {"task": "both", "epochs": 4,
            "seed": 0, "folds": 3, "width": 4, "device": "cpu", "rows": ["day"]},
            "smoke": True, "label": "smoke", "not_the_paper": ["UNet width 4 (paper: 32)"],
            "folds": FOLDS, "rows": rows, "seeds": [0], "compare_to": "day",
            "protocol": {"protocol": "paper", "targets": "release", "noise": "model",
                         "synth_iso": "alternate", "amp": None, "channels_last": False,
                         "folds_file": None},
            "bootstrap": {"replicates": 2000, "level": 0.95, "seed": 0,
                          "method": "scenes resampled within folds"},
            "comparisons": comps,
            "left_out": [{"task": "noisy", "row": "fresh", "why": "--targets release"}]}


def format1(t):
    """The same table as an earlier version wrote it (format /1: no new field)."""
    old = copy.deepcopy({k: t[k] for k in ("config", "smoke", "not_the_paper", "folds")})
    old["format"] = "day2night-experiment-table/1"
    old["rows"] = [{k: r[k] for k in ("task", "row", "label", "mean")}
                   | {"units": [{k: v for k, v in u.items() if k != "seed"}
                                for u in r["units"]]}
                   for r in t["rows"] if r["row"] not in ("untrained", "burst")]
    return old


def write_images(out, t, scenes):
    """The report's PNGs of ``scenes`` as unit.score_unit writes them, for every row."""
    rng = np.random.default_rng(0)
    for r in t["rows"]:
        for u in r["units"]:
            for sid in set(scenes) & set(u["test_scenes"]):
                for key in KEYS[r["task"]]:
                    x = rng.random((24, 32, 3), dtype=np.float32)
                    y = (rng.random((24, 32, 3)) * 255).astype(np.uint8)
                    pred = (rng.random((24, 32, 3)) * 255).astype(np.uint8)
                    _report_images(out / "img" / r["task"], r["row"], f"{sid}_{key}", x, y,
                                   pred)


@pytest.fixture()
def page(tmp_path):
    t = table()
    scenes, _ = report.scenes_to_show(FOLDS, 3)
    write_images(tmp_path, t, scenes)
    report.write(tmp_path, t, ["clean", "noisy"], scenes, show=3)
    return tmp_path, t, scenes


class Tags(html.parser.HTMLParser):
    """Every start tag with its attributes, and the text outside <script>/<style>/<svg>."""

    def __init__(self):
        super().__init__()
        self.tags, self.text, self._skip = [], [], 0

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        self._skip += tag in ("script", "style")

    def handle_endtag(self, tag):
        self._skip -= tag in ("script", "style")

    def handle_data(self, data):
        if not self._skip:
            self.text.append(data)


def parse(path):
    p = Tags()
    p.feed(pathlib.Path(path).read_text())
    return p


def test_show_n_takes_scenes_from_every_fold():
    assert report.scenes_to_show(FOLDS, 3) == (["s0", "s2", "s4"], None)
    assert report.scenes_to_show(FOLDS, 4)[0] == ["s0", "s2", "s4", "s1"]
    assert report.scenes_to_show(FOLDS, 0) == ([], None)
    scenes, why = report.scenes_to_show(FOLDS, 9)
    assert scenes == ["s0", "s2", "s4", "s1", "s3"]
    assert why.startswith("--show 9: showing 5 test scene(s)")


def test_every_row_shows_every_chosen_scene(page):
    out, t, scenes = page
    p = parse(out / "index.html")
    srcs = [a["src"] for tag, a in p.tags if tag == "img"]
    for r in t["rows"]:
        for sid in scenes:
            for key in KEYS[r["task"]]:
                for src in (f"img/{r['task']}/{r['row']}/{sid}_{key}_pred.png",
                            f"img/{r['task']}/scenes/{sid}_{key}_target.png"):
                    assert src in srcs, src
    assert all((out / s).is_file() for s in srcs)


def test_fewer_scenes_than_asked_is_said_on_the_page(tmp_path):
    t = table()
    scenes, why = report.scenes_to_show(FOLDS, 8)
    report.write(tmp_path, t, ["clean", "noisy"], scenes, show=8)
    text = " ".join(parse(tmp_path / "index.html").text)
    assert why in text and "--show 8: showing 5 test scene(s)" in text


def test_best_value_per_column_skips_the_reference_rows(page):
    out, t, _ = page
    rows = [r for r in t["rows"] if r["task"] == "noisy"]
    # the burst row is the highest PSNR and lowest Delta E but is not ranked
    assert report_tables.best(rows, "1600", "psnr", +1) == pytest.approx(
        rows[3]["scores"]["1600"]["psnr"]["mean"])
    assert report_tables.best(rows, "1600", "delta_e", -1) == pytest.approx(
        rows[3]["scores"]["1600"]["delta_e"]["mean"])
    src = (out / "index.html").read_text()
    burst = src.split('<tr class="burst">')[1].split("</tr>")[0]
    untrained = src.split('<tr class="untrained">')[1].split("</tr>")[0]
    assert 'class="best"' not in burst and 'class="best"' not in untrained
    # clean: 3 metrics, noisy: 2 inputs x 3 metrics, each marked once (on Supervised)
    assert src.count('<td class="best">') == 9


def test_labels_are_escaped_and_tables_are_html(page):
    out, _, _ = page
    src = (out / "index.html").read_text()
    assert "Day &lt;b&gt;&amp;" in src and "Day <b>&" not in src
    # nothing from the network: the only URL is the SVG namespace
    assert src.replace('xmlns="http://www.w3.org/2000/svg"', "").count("://") == 0
    p = parse(out / "index.html")
    classes = [a.get("class") for tag, a in p.tags if tag == "table"]
    assert classes.count("scores") == 2 and classes.count("comparisons") == 1
    assert not [tag for tag, _ in p.tags if tag == "pre"]
    text = "\n".join(p.text)
    assert "41.16" in text and "0.9215" in text  # the paper's numbers beside
    assert "--targets release" in text and "scenes resampled within folds" in text
    assert "better" in text and "not distinguishable" in text and "worse" in text


def test_format_1_table_renders_with_dashes(tmp_path):
    t = format1(table())
    report.write(tmp_path, t, ["clean", "noisy"], ["s0"], show=1)
    p = parse(tmp_path / "index.html")
    text = "\n".join(p.text)
    assert "has no comparisons" in text
    assert [a.get("class") for tag, a in p.tags if tag == "table"].count("scores") == 2
    assert "26.20" in text  # the mean of format /1 is shown
    assert 'class="ci"' not in (tmp_path / "index.html").read_text()


def test_curves_are_small_multiples_with_distinct_colours(page):
    out, t, _ = page
    svg = (out / "curves_clean.svg").read_text()
    lines = curves.series(t, "clean")
    assert [label for label, _ in lines] == ["Day <b>&", "Ours", "Supervised (k-fold)"]
    sup = lines[2][1]
    assert [name for name, _, _ in sup] == ["fold 0, seed 0", "fold 1, seed 0",
                                           "fold 2, seed 0"]
    # every unit: a train line (4 epochs) and a validation line (epoch 0 = initial)
    assert all(len(tr) == 4 and len(va) == 5 and va[0] == (0, 0.45) for _, tr, va in sup)
    assert svg.count("<polyline") == 2 * (1 + 1 + 3)
    assert svg.count('stroke-dasharray="4 3"') == 1 + 1 + 3
    charts = svg.split("<svg ")[2:]
    assert len(charts) == 3
    for c in charts:
        fills = [s.split('fill="')[1].split('"')[0] for s in c.split("<rect x=")[1:]]
        assert len(set(fills)) == len(fills) == len(c.split("<polyline")[1:]) // 2
    assert len(set(curves.colours(14))) == 14


def need_tensorboard():
    """tensorboard's EventAccumulator: tensorboard is in the train requirements
    (python/tests/requirements-train.txt), so it is required where torch is
    (D2N_REQUIRE_TORCH=1), else the test skips with the reason."""
    try:
        from tensorboard.backend.event_processing.event_accumulator import EventAccumulator
    except ImportError as e:
        if os.environ.get("D2N_REQUIRE_TORCH") == "1":
            pytest.fail(f"D2N_REQUIRE_TORCH=1 but tensorboard cannot be imported: {e}")
        pytest.skip(f"tensorboard is not installed ({e}; the train extra has it)")
    return EventAccumulator


def test_tensorboard_events_hold_the_history(page):
    accumulator = need_tensorboard()
    out, t, _ = page
    sup = next(r for r in t["rows"] if (r["task"], r["row"]) == ("noisy", "supervised"))
    for u in sup["units"]:
        acc = accumulator(str(out / "tb" / "noisy" / "supervised" / u["fold"]))
        acc.Reload()
        assert sorted(acc.Tags()["scalars"]) == ["train/loss", "val/l1", "val/psnr"]
        loss = [(s.step, s.value) for s in acc.Scalars("train/loss")]
        assert loss == [(h["epoch"] + 1, pytest.approx(h["loss"], rel=1e-6))
                        for h in u["history"]]
        val = [(s.step, s.value) for s in acc.Scalars("val/l1")]
        assert val[0] == (0, pytest.approx(0.45))
        assert val[1:] == [(h["epoch"] + 1, pytest.approx(h["val_loss"], rel=1e-6))
                           for h in u["history"]]
        assert [s.value for s in acc.Scalars("val/psnr")][1:] == pytest.approx(
            [h["val_psnr"] for h in u["history"]])
    # no history, no run folder; a rewrite replaces the tree (no duplicated events)
    assert not (out / "tb" / "clean" / "untrained").exists()
    report.write(out, t, ["clean", "noisy"], [], show=0)
    acc = accumulator(str(out / "tb" / "clean" / "day" / "all"))
    acc.Reload()
    assert len(acc.Scalars("train/loss")) == 4
    assert not [p for p in out.iterdir() if p.name.startswith(".tb.")]


def test_several_seeds_get_a_folder_each(tmp_path):
    need_tensorboard()
    t = table()
    r = next(r for r in t["rows"] if (r["task"], r["row"]) == ("clean", "ours"))
    second = copy.deepcopy(r["units"][0]) | {"seed": 1}
    r["units"].append(second)
    assert tb.write(tmp_path, t) == 1 + 2 + 3 + 1 + 1 + 3
    assert sorted(p.name for p in (tmp_path / "tb" / "clean" / "ours" / "all").iterdir()) == [
        "seed-0", "seed-1"]


def test_without_tensorboard_the_log_says_so_once(page, monkeypatch, capsys):
    out, t, scenes = page
    monkeypatch.setattr(tb, "MISSING", "No module named 'tensorboard'")
    capsys.readouterr()
    report.write(out, t, ["clean", "noisy"], scenes, show=3)
    err = capsys.readouterr().err
    assert err.count("tb/ not written") == 1 and "not installed" in err
    assert (out / "index.html").is_file()


def test_grid_has_column_headers_and_per_scene_scores(page):
    out, t, scenes = page
    src = (out / "index.html").read_text()
    assert src.count('<table class="grid">') == len(t["rows"])
    assert src.count('<table class="per-scene">') == len(t["rows"])
    for head in report_grid.COLUMNS:
        assert f'<th scope="col">{head}</th>' in src


def test_page_in_headless_chromium(page):
    chromium = require_tool("chromium", "chromium")
    out, t, scenes = page
    got = browser_checks(chromium, out / "index.html")
    assert got["tables"].count("scores") == 2 and "comparisons" in got["tables"]
    assert got["tables"].count("grid") == len(t["rows"])
    assert got["pre"] == 0  # no preformatted text (counted before the check adds its own)
    assert markdown_visible(got["text"]) == []
    assert got["images"] == sum(4 * len(KEYS[r["task"]]) * len(scenes) for r in t["rows"])
    assert got["broken"] == []
    assert got["headers"][1:5] == ["input", "prediction", "target", "Delta E 2000"]
    assert len(got["best"]) == 9 and got["svgs"] >= 2 * 3
    if os.environ.get("D2N_EXPERIMENT_SCREENSHOT"):
        screenshot(chromium, out / "index.html", os.environ["D2N_EXPERIMENT_SCREENSHOT"])


def test_the_browser_check_can_fail(page):
    chromium = require_tool("chromium", "chromium")
    out, _, _ = page
    victim = sorted((out / "img" / "clean" / "day").glob("*_pred.png"))[0]
    victim.write_bytes(b"not a png")
    (out / "md.html").write_text("<!doctype html><body><pre>| a |\n|---|\n## Table 1\n**x**"
                                 f'</pre><img src="img/clean/day/{victim.name}"></body>')
    got = browser_checks(chromium, out / "md.html")
    assert got["broken"] == [f"img/clean/day/{victim.name}"]
    assert markdown_visible(got["text"]) == ["|---|", "**", "## Table 1"]
