"""The report page's addresses, file modes, Delta E colours, table of contents and its
agreement with table.md (issue 47, "The page"): a scene named ``a#b?c%zz`` loads its images,
every file and folder the report writes has the umask's mode, the Delta E maps are in the
viridis scale with the scale bar on the page, the protocol line, columns, rounding and seeds
columns are table.md's, and every link of the contents points at a heading of the page.
Built from test_experiment_report's hand-made table.json and real PNGs (no training)."""

import os
import pathlib
import re
import stat
import urllib.parse

import numpy as np
import pytest

import test_experiment_report as base
from conftest import require_tool
from report_browser import browser_checks

from day2night.atomic import create_temp, create_temp_dir, write_bytes
from day2night.experiment import demap, report, table, tabletext, unit
from day2night.png import read_png, write_png

ODD = "a#b?c%zz"


def rename(obj, old, new):
    """``obj`` (table.json) with the scene ``old`` called ``new`` everywhere."""
    if isinstance(obj, dict):
        return {k: rename(v, old, new) for k, v in obj.items()}
    if isinstance(obj, list):
        return [rename(v, old, new) for v in obj]
    return new if obj == old else obj


@pytest.fixture()
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


@pytest.fixture()
def odd_page(tmp_path, umask_022):
    """The report of a table whose scene s0 is named ``a#b?c%zz``, written under umask 022."""
    t = rename(base.table(), "s0", ODD)
    scenes, _ = report.scenes_to_show(t["folds"], 3)
    assert ODD in scenes
    base.write_images(tmp_path, t, scenes)
    report.write(tmp_path, t, ["clean", "noisy"], scenes, show=3)
    table.write(tmp_path, t)
    return tmp_path, t, scenes


def modes(root):
    """{relative path: permission bits} of every file and folder under ``root``."""
    out = {}
    for p in sorted(pathlib.Path(root).rglob("*")):
        if not p.is_symlink():
            out[str(p.relative_to(root))] = stat.S_IMODE(p.stat().st_mode)
    return out


def wrong_modes(root, file_mode=0o644, dir_mode=0o755):
    return {k: oct(m) for k, m in modes(root).items()
            if m != (dir_mode if (pathlib.Path(root) / k).is_dir() else file_mode)}


def test_image_addresses_are_url_encoded_and_resolve(odd_page):
    out, t, scenes = odd_page
    p = base.parse(out / "index.html")
    srcs = [a["src"] for tag, a in p.tags if tag == "img"]
    odd = [s for s in srcs if "a%23b%3Fc%25zz" in s]
    # every row tested the scene (synthetic rows: all scenes; per-fold rows: fold 0's)
    assert len(odd) == sum(4 * len(base.KEYS[r["task"]]) for r in t["rows"])
    # every reference to the odd scene is encoded; none is left raw (# or ? in a src)
    assert not [s for s in srcs if "#" in s or "?" in s]
    for s in srcs:
        assert (out / urllib.parse.unquote(s)).is_file(), s
    src = (out / "index.html").read_text()
    assert 'src="img/clean/scenes/a%23b%3Fc%25zz_clean_input.png"' in src
    assert report.report_grid.url("img/x/<a&b> c.png") == "img/x/%3Ca%26b%3E%20c.png"


def test_every_file_the_report_writes_has_the_umask_mode(odd_page):
    out, _, _ = odd_page
    found = modes(out)
    assert "index.html" in found and "table.md" in found and "table.json" in found
    assert any(k.startswith("img/") and k.endswith("_de.png") for k in found)
    if report.tb.MISSING is None:
        assert any(k.startswith("tb/") for k in found)
    assert wrong_modes(out) == {}


def test_atomic_writes_follow_the_umask(tmp_path):
    old = os.umask(0o027)
    try:
        write_bytes(tmp_path / "sub" / "f.bin", b"x")
        fd, path = create_temp(tmp_path, ".t.")
        os.close(fd)
        d = create_temp_dir(tmp_path, ".d.")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "sub" / "f.bin").stat().st_mode) == 0o640
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o640
    assert re.fullmatch(r"\.t\.[0-9a-f]{8}\.tmp", os.path.basename(path))
    assert stat.S_IMODE(d.stat().st_mode) == 0o750
    # O_EXCL: an existing name is never reused
    names = {create_temp_dir(tmp_path, ".e.").name for _ in range(20)}
    assert len(names) == 20


def test_delta_e_maps_are_viridis_on_a_log_scale():
    # the colour map's ends and middle: matplotlib's viridis entries 0, 128 and 255
    assert demap.LUT.shape == (256, 3)
    assert demap.LUT[0].tolist() == [68, 1, 84]
    assert demap.LUT[128].tolist() == [33, 145, 140]
    assert demap.LUT[255].tolist() == [253, 231, 37]
    de = np.array([[0.0, 1.0, 9.0, 50.0, 1e6, np.nan, -3.0]])
    img = unit.heat(de)
    assert img.shape == (1, 7, 3) and img.dtype == np.uint8
    level = [round(np.log1p(min(max(v, 0), 50)) / np.log1p(50) * 255) for v in
             (0.0, 1.0, 9.0, 50.0, 50.0, 50.0, 0.0)]
    assert [demap.LUT[i].tolist() for i in level] == img[0].tolist()
    # no map colour is white or near it: large errors never look like a missing image
    assert demap.LUT.min(axis=1).max() < 100 and (demap.LUT.sum(axis=1) < 3 * 200).all()
    # luminance rises with the error (a perceptual, ordered scale)
    y = demap.LUT @ np.array([0.2126, 0.7152, 0.0722])
    assert (np.diff(y) > -0.5).all() and y[-1] > y[0] + 150


def test_the_maps_on_disk_and_the_scale_bar_on_the_page(odd_page):
    out, _, _ = odd_page
    de = sorted((out / "img").rglob("*_de.png"))
    assert de
    px = read_png(de[0]).reshape(-1, 3)
    lut = {tuple(c) for c in demap.LUT.tolist()}
    assert {tuple(c) for c in px.tolist()} <= lut
    src = (out / "index.html").read_text()
    assert src.count('<svg class="scale"') == 1
    text = " ".join(base.parse(out / "index.html").text)
    assert "viridis" in text and f"to {demap.DE_MAX:g} or more" in text
    bar = src.split('<svg class="scale"')[1].split("</svg>")[0]
    assert [int(x.rstrip("+")) for x in re.findall(r'>(\d+\+?)</text>', bar)] == \
        list(demap.TICKS)


def test_protocol_line_is_table_md_sentence(odd_page):
    out, t, _ = odd_page
    sentence = tabletext.protocol_sentence(t["protocol"])
    assert sentence.startswith("paper (targets release, noise model, synthetic ISO alternate")
    assert f"Protocol: {sentence}" in (out / "table.md").read_text()
    text = " ".join(base.parse(out / "index.html").text)
    assert sentence in text and "channels_last False" not in text


def test_page_and_table_md_have_the_same_columns_and_rounding(odd_page):
    out, t, _ = odd_page
    md = (out / "table.md").read_text()
    src = (out / "index.html").read_text()
    for task in ("clean", "noisy"):
        cols = tabletext.columns(task)
        assert [m for _, m in cols].count("delta_e") == len(tabletext.inputs_of(task))
        # table.md: one column per (input, metric), after model and scenes / seeds
        title = "Table 1" if task == "clean" else "Table 2"
        head = md.split(f"## {title}")[1].split("\n")[2]
        cells = [c.strip() for c in head.strip("|").split("|")]
        assert cells[:2] == ["model", "scenes / seeds"] and len(cells) == len(cols) + 4
        # the page: the same metrics per input
        page = src.split(f'id="table-{task}"')[1].split("</thead>")[0]
        assert page.count("&uarr;</th>") + page.count("&darr;</th>") == len(cols)
    # the same rounding: a Delta E difference of -0.0001 and one of -0.00003
    t["comparisons"][2].update(mean=-0.0001, ci_low=-0.00003, ci_high=-0.00001)
    report.write(out, t, ["clean"], [], show=0)
    md, src = table.markdown(t), (out / "index.html").read_text()
    for s in ("-0.0001", "[-3e-05, -1e-05]"):
        assert s in md and s in src
    assert "-0.000 " not in src and "0.0000, -0.0000" not in md


def test_seeds_columns_are_counts(odd_page, tmp_path):
    _, t, _ = odd_page
    for c in t["comparisons"]:
        c["seeds"] = [7, 8]
    for r in t["rows"]:
        for k in r["scores"].values():
            for s in k.values():
                s["seeds"] = [7, 8]
    out = tmp_path / "two"
    report.write(out, t, ["clean", "noisy"], [], show=0)
    src = (out / "index.html").read_text()
    row = src.split('<table class="comparisons">')[1].split("</tr>")[1]
    assert '<td title="seeds 7, 8">2</td>' in row and "7, 8</td>" not in row
    assert '<td title="seeds 7, 8">5 / 2</td>' in src
    md = table.markdown(t)
    assert "| 5 / 2 |" in md and "| 5 | 2 | better |" in md


def test_table_of_contents_links_every_section(odd_page):
    out, t, _ = odd_page
    src = (out / "index.html").read_text()
    nav = src.split('<nav class="toc"')[1].split("</nav>")[0]
    hrefs = re.findall(r'href="#([^"]+)"', nav)
    ids = set(re.findall(r' id="([^"]+)"', src))
    assert hrefs and set(hrefs) <= ids
    for section in ("run", "table-clean", "table-noisy", "comparisons", "curves", "scenes",
                    "scenes-noisy-burst"):
        assert section in hrefs
    assert len(hrefs) == len(set(hrefs))
    # the contents come before the first section
    assert src.index('<nav class="toc"') < src.index('<h2 id="run">')


def test_page_in_headless_chromium_with_an_odd_scene_name(odd_page):
    chromium = require_tool("chromium", "chromium")
    out, t, scenes = odd_page
    got = browser_checks(chromium, out / "index.html")
    assert got["images"] == sum(4 * len(base.KEYS[r["task"]]) * len(scenes)
                                for r in t["rows"])
    assert got["broken"] == []
    assert len(got["toc"]) >= 6 and got["unresolved"] == []
    assert wrong_modes(out) == {}


def test_the_toc_check_can_fail(tmp_path):
    chromium = require_tool("chromium", "chromium")
    (tmp_path / "p.html").write_text('<!doctype html><body><nav class="toc"><a href="#here">a'
                                     '</a><a href="#gone">b</a></nav><h2 id="here">x</h2>'
                                     '<img src="a#b.png"><img src="a%23b.png"></body>')
    write_png(tmp_path / "a#b.png", np.zeros((4, 4, 3), np.uint8))
    got = browser_checks(chromium, tmp_path / "p.html")
    # the raw name is a fragment and does not load; the encoded one does
    assert got["unresolved"] == ["#gone"] and got["broken"] == ["a#b.png"]
