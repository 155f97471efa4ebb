"""The variants are named once (day2night/variants.py): no code in experiment/ or train/
compares a value with a variant's literal name ("release", "day2night", "alternate",
"simple"), and a member behaves as its name wherever a string went before (dict keys, sets,
JSON, argparse choices, f-strings, inspect.signature)."""

import argparse
import ast
import inspect
import json
import pathlib
import subprocess
import sys

import pytest

from day2night import variants
from day2night.experiment import pairs
from day2night.train import targets

PKG = pathlib.Path(variants.__file__).resolve().parent
NAMES = {m.value for cls in variants.Variant.__subclasses__() for m in cls}
#: Comparisons allowed by file and source text: none (the release-conflicts check of
#: render_target is ``release::conflicts`` through the extension).
ALLOWED = set()


def _literals(node):
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return [v for e in node.elts for v in _literals(e)]
    return []


def literal_comparisons(text, rel):
    """(rel, line, source) of each comparison (==, !=, in, not in, is) of a value with a
    variant's literal name in the Python source ``text``."""
    out = []
    for node in ast.walk(ast.parse(text, rel)):
        if not isinstance(node, ast.Compare):
            continue
        if any(v in NAMES for x in [node.left, *node.comparators] for v in _literals(x)):
            src = ast.get_source_segment(text, node)
            if (rel, src) not in ALLOWED:
                out.append((rel, node.lineno, src))
    return out


def test_no_literal_variant_comparison_in_experiment_and_train():
    found = []
    for folder in ("experiment", "train"):
        for f in sorted((PKG / folder).glob("*.py")):
            rel = f.relative_to(PKG).as_posix()
            found += literal_comparisons(f.read_text(encoding="utf-8"), rel)
    assert not found, "compare with day2night.variants' members: " + "; ".join(
        f"{r}:{n}: {s}" for r, n, s in found)


def test_a_planted_comparison_is_found():
    planted = ('def f(noise, isp, layout, targets):\n'
               '    if noise == "release":\n'
               '        pass\n'
               '    a = "day2night" != isp\n'
               '    b = layout in ("simple", "other")\n'
               '    c = targets == Isp.RELEASE and noise == "fresh"\n'
               '    return {"release": a}\n')
    found = literal_comparisons(planted, "experiment/planted.py")
    assert [n for _, n, _ in found] == [2, 4, 5]
    assert found[0][2] == 'noise == "release"'
    # no file is exempt
    assert literal_comparisons('isp == "release"\n', "experiment/x.py")
    assert literal_comparisons('isp == "release"\n', "train/targets.py")


def test_members_behave_as_their_names():
    Isp = variants.Isp
    assert Isp.RELEASE == "release" and "release" == Isp.RELEASE and Isp("release") is Isp.RELEASE
    assert {Isp.RELEASE: 1}["release"] == 1 and {"release": 2}[Isp.RELEASE] == 2
    assert {Isp.RELEASE} == {"release"} and Isp.RELEASE in "render_png(release)"
    assert json.dumps({Isp.DAY2NIGHT: [variants.Noise.RELEASE]}) == '{"day2night": ["release"]}'
    assert (str(Isp.RELEASE), f"{Isp.RELEASE:>8}", repr(Isp.RELEASE)) == (
        "release", " release", "'release'")
    p = argparse.ArgumentParser(prog="x")
    p.add_argument("--targets", choices=list(Isp))
    assert "{release,day2night}" in p.format_help()
    assert p.parse_args(["--targets", "release"]).targets == Isp.RELEASE
    with pytest.raises(SystemExit):
        p.parse_args(["--targets", "neither"])


@pytest.mark.parametrize("fn, text", [
    (pairs.synth_pairs, "(day_path, mode, seed, isos=(1600, 3200), targets='day2night', "
                        "noise='day2night')"),
    (targets.render_target, "(raw, neutral=None, demosaic='mhc', tone='srgb', "
                            "isp='day2night', orient=True)"),
])
def test_signatures_read_as_before(fn, text):
    assert str(inspect.signature(fn)) == text


def test_help_texts_read_the_presets():
    """The training options' help texts are made from presets.py's values: changed there,
    the help follows (a fresh interpreter imports config.py after the change)."""
    code = ("from day2night.experiment import presets\n"
            "presets.PAPER.update(epochs=501, width=33, patch=80, batch=129, lr=2e-3)\n"
            "presets.PRESETS['mini'].update(epochs=41, width=9, patch=48, batch=7, lr=3e-2)\n"
            "presets.PAPER_FOLDS = 4\n"
            "import dataclasses\n"
            "from day2night.experiment import config\n"
            "for f in dataclasses.fields(config.ExperimentConfig):\n"
            "    print(f.name, '|', f.metadata['help'], '|', f.metadata['default_from'])\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    lines = {ln.split(" | ")[0]: ln for ln in out.splitlines()}
    assert "paper and default: 501; --preset mini: 41" in lines["epochs"]
    assert "paper and default: 33;" in lines["width"] and "mini: 9)" in lines["width"]
    assert "default and paper: 4;" in lines["folds"] and "'fold file', 4)" in lines["folds"]
    assert "width 9, 48 x 48 patches, batch 7, lr 3e-2, 41 epochs" in lines["preset"]
    assert "(paper: 80;" in lines["patch"] and "(paper: 129)" in lines["batch"]
    assert "(paper: 2e-3)" in lines["lr"]
