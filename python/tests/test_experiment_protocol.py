"""The release's protocol on request (issue 35): its fold lists read from its pickle without
running pickle code, its noise on synthetic noisy inputs, its ISO draw, and the choice of the
ISP that renders the targets."""

import dataclasses
import json
import os
import pickle

import numpy as np
import pytest

from conftest import ROOT, need_torch
from day2night.experiment import folds, protocol, release_folds, release_noise


def release_lists(n=105, k=3, val=10):
    """Lists shaped like the release's k_fold_indices_saved.p: sorted, train and val entries
    numpy int32 scalars, test entries Python ints."""
    perm = np.random.RandomState(7).permutation(n)
    out = {key: [] for key in release_folds.KEYS}
    for i in range(k):
        test = sorted(int(j) for j in perm[i::k])
        rest = [j for j in range(n) if j not in set(test)]
        vals = sorted(rest[j] for j in np.random.RandomState(i).permutation(len(rest))[:val])
        train = [j for j in rest if j not in set(vals)]
        out["train_index_all"].append([np.int32(j) for j in train])
        out["val_index_all"].append([np.int32(j) for j in vals])
        out["test_index_all"].append(test)
    return out


def plain(lists):
    return {k: [[int(j) for j in f] for f in v] for k, v in lists.items()}


def test_the_release_pickle_gives_its_lists_mapped_to_scene_ids(tmp_path):
    lists = release_lists()
    path = tmp_path / "k_fold_indices_saved.p"
    path.write_bytes(pickle.dumps(lists))
    read = release_folds.read_release_folds(path)
    assert read == plain(lists)
    assert [len(f) for f in read["train_index_all"]] == [60, 60, 60]
    assert [len(f) for f in read["val_index_all"]] == [10, 10, 10]
    assert [len(f) for f in read["test_index_all"]] == [35, 35, 35]
    scenes = ["%03d" % j for j in range(105)]
    m = release_folds.to_manifest(read, scenes, source=path)
    folds.check_folds(m)
    for i, s in enumerate(m["splits"]):
        for key, part in release_folds.PARTS.items():
            assert s[part] == ["%03d" % j for j in lists[key][i]]
    # every pickle protocol the release's Python could have written (2 adds _codecs)
    for proto in (3, 4, 5):
        path.write_bytes(pickle.dumps(lists, protocol=proto))
        assert release_folds.read_release_folds(path) == plain(lists)


class _Evil:
    def __init__(self, flag):
        self.flag = flag

    def __reduce__(self):
        return (os.system, (f"touch {self.flag}",))


def test_a_pickle_with_any_other_global_is_refused_without_running_it(tmp_path):
    flag = tmp_path / "ran"
    evil = release_lists()
    evil["test_index_all"][0][0] = _Evil(flag)
    path = tmp_path / "evil.p"
    path.write_bytes(pickle.dumps(evil))
    with pytest.raises(folds.FoldError, match=r"evil\.p: refused: .*system.*only numpy"):
        release_folds.read_release_folds(path)
    assert not flag.exists()
    path.write_bytes(pickle.dumps({"train_index_all": np.arange(3)}))  # an ndarray: reconstruct
    with pytest.raises(folds.FoldError, match="refused"):
        release_folds.read_release_folds(path)
    path.write_bytes(b"\x80\x04garbage")
    with pytest.raises(folds.FoldError, match=r"evil\.p: refused: not the release's "
                       "fold-index pickle .byte 2: opcode GET"):
        release_folds.read_release_folds(path)


def test_the_json_export_round_trips(tmp_path):
    src = tmp_path / "k.p"
    src.write_bytes(pickle.dumps(release_lists()))
    out = tmp_path / "k.json"
    assert release_folds.main(["export", str(src), "-o", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["format"] == release_folds.FORMAT
    assert release_folds.read_release_folds(out) == release_folds.read_release_folds(src)


@pytest.mark.parametrize("edit, msg", [
    (lambda d: d.pop("val_index_all"), "missing val_index_all"),
    (lambda d: d.update(extra=1), "unknown extra"),
    (lambda d: d["test_index_all"].pop(), "different numbers of folds"),
    (lambda d: d["train_index_all"][0].append(-1), "-1 is not a scene index"),
    (lambda d: d["train_index_all"][0].append(True), "True is not a scene index"),
    (lambda d: d["val_index_all"].__setitem__(1, 5), r"val_index_all\[1\] is not a list"),
])
def test_malformed_lists_are_named(tmp_path, edit, msg):
    d = plain(release_lists())
    edit(d)
    p = tmp_path / "k.json"
    p.write_text(json.dumps(d))
    with pytest.raises(folds.FoldError, match=msg):
        release_folds.read_release_folds(p)


def test_lists_that_do_not_fit_the_real_set_are_named(tmp_path):
    lists = plain(release_lists())
    with pytest.raises(folds.FoldError, match="index 104 names scene number 105.*has 100"):
        release_folds.to_manifest(lists, ["%03d" % j for j in range(100)], source="k.p")
    lists["test_index_all"][1].append(lists["test_index_all"][0][0])
    with pytest.raises(folds.FoldError, match="k.p: fold 1: scene"):
        release_folds.to_manifest(lists, ["%03d" % j for j in range(105)], source="k.p")


def test_protocol_presets_and_flags(tmp_path):
    from day2night.experiment import config

    def resolved(**kw):
        base = config.ExperimentConfig(day=str(tmp_path), real=str(tmp_path), output="o")
        return config.resolve(dataclasses.replace(base, **kw))[0]

    p = resolved()
    assert (p.protocol, p.targets, p.noise, p.synth_iso, p.folds_file, p.folds) == \
        ("day2night", "day2night", "day2night", "alternate", None, 3)
    with pytest.raises(protocol.ProtocolError, match="--protocol release needs --folds-file"):
        resolved(protocol="release")
    k = tmp_path / "k.p"
    k.write_bytes(pickle.dumps(release_lists()))
    r = resolved(protocol="release", folds_file=str(k))
    assert (r.targets, r.noise, r.synth_iso, r.folds_file, r.folds) == \
        ("release", "release", "release", str(k.resolve()), 3)
    assert len(r.folds_sha256) == 64
    r = resolved(protocol="release", folds_file=str(k), targets="day2night",
                 synth_iso="alternate")
    assert (r.targets, r.noise, r.synth_iso) == ("day2night", "release", "alternate")
    with pytest.raises(protocol.ProtocolError, match="--targets 'srgb'"):
        resolved(targets="srgb")
    with pytest.raises(protocol.ProtocolError, match="cannot read"):
        resolved(folds_file=str(tmp_path / "absent.p"))
    # each protocol default is one field's metadata: its sources, in order
    sources = {f.name: f.metadata["default_from"]
               for f in dataclasses.fields(config.ExperimentConfig)}
    assert sources["targets"] == ("protocol", "real set")
    assert sources["noise"] == sources["synth_iso"] == ("protocol",)
    assert sources["folds"] == ("fold file", 3)


def test_the_targets_default_follows_the_real_sets_targets(tmp_path):
    def record(sid, stages):
        return json.dumps({"kind": "real", "scene": sid, "status": "ok", "stages": stages})

    (tmp_path / "manifest.jsonl").write_text(
        record("000", ["clean_raw_png", "check_motion", "write_clean_raw", "copy_target_png"])
        + "\n" + record("001", ["clean_raw_png", "write_clean_raw", "copy_target_png"]) + "\n")
    assert protocol.real_target_isp(tmp_path) == "release"
    with open(tmp_path / "manifest.jsonl", "a") as f:
        f.write(record("002", ["merge", "check_motion", "write_clean_raw", "render_png"]) + "\n")
    assert protocol.real_target_isps(tmp_path) == {"000": "release", "001": "release",
                                                   "002": "day2night"}
    assert protocol.real_target_isp(tmp_path) == "day2night"
    # a target real-pairs rendered with the release's ISP (its scene record says so)
    meta = tmp_path / "real" / "meta"
    meta.mkdir(parents=True)
    (meta / "002.json").write_text(json.dumps({"target": {"png": "render", "isp": "release"}}))
    assert protocol.real_target_isp(tmp_path) == "release"


def test_the_iso_is_drawn_per_image_like_the_release():
    names = [f"day_{i:02d}.dng" for i in range(70)]
    isos = protocol.release_isos(reversed(names), seed=4)
    assert list(isos) == names  # sorted, as prepare_data.py loops over the images
    draws = np.random.RandomState(4).randint(2, size=70)
    assert [isos[n] for n in names] == [(1600, 3200)[k] for k in draws]
    assert protocol.release_isos(names, seed=4) == isos
    assert protocol.release_isos(names, seed=5) != isos
    slots = [{"kind": "synthetic", "id": names[3], "iso": 1600},
             {"kind": "real", "id": "007", "iso": 3200}]
    out = protocol.with_isos(slots, isos)
    assert out[0]["iso"] == isos[names[3]] and out[1]["iso"] == 3200


def test_the_noise_table_is_the_projects_embedded_one():
    table = json.loads((ROOT / "calibration" / "samsung-s20fe" / "noise.json").read_text())
    dn = table["dn_table"]
    assert (dn["black"], dn["white"]) == (64.0, 1023.0)
    for iso, pos, b1, b2 in dn["rows"]:
        assert release_noise.DN_TABLE[iso][pos] == (b1, b2)
    assert len(dn["rows"]) == 4 * len(release_noise.DN_TABLE)


def test_release_noise_is_the_tables_variance_clipped_at_1023_and_truncated():
    n = 1024  # 131072 samples per position on the left: the mean within 0.09 (1 sigma)
    plane = np.full((n, n), 500, np.uint16)
    plane[:, n // 2:] = 1020
    rng = np.random.RandomState(release_noise.noise_key(0, "day.dng", 1600))
    noisy = release_noise.add_release_noise(plane, 1600, rng)
    assert noisy.dtype == np.uint16 and noisy.max() <= 1023
    left = noisy[:, : n // 2].astype(np.float64)
    for p, (b1, b2) in enumerate(release_noise.DN_TABLE[1600]):
        i, j = divmod(p, 2)
        site = left[i::2, j::2]
        # truncation: the mean is half a code low; the variance is the table's (+1/12)
        assert site.mean() == pytest.approx(500 - 0.5, abs=0.3)
        assert site.var() == pytest.approx(b1 * 500 + b2 + 1 / 12, rel=0.02)
    assert (noisy[:, n // 2:] == 1023).mean() > 0.3  # clipped at 1023
    again = release_noise.add_release_noise(
        plane, 1600, np.random.RandomState(release_noise.noise_key(0, "day.dng", 1600)))
    assert np.array_equal(noisy, again)
    bright = np.full((4, 4), 4000, np.uint16)  # a 12-bit camera's highlight: the release clips
    assert (release_noise.add_release_noise(bright, 3200, np.random.RandomState(1)) == 1023).all()
    with pytest.raises(ValueError, match="ISO 6400"):
        release_noise.add_release_noise(plane, 6400, rng)


def test_release_noise_leaves_the_masked_border():
    stored = np.full((12, 10), 300, np.uint16)
    out = release_noise.release_noisy_plane(stored, [2, 4, 12, 10], 3200, 9)
    assert (out[:2] == 300).all() and (out[:, :4] == 300).all()
    assert (out[2:, 4:] != 300).any()


def tiny_real_set(root, n):
    """A real set of ``n`` scenes ``000``.. in real-pairs' layout (16 x 16 stand-ins: one
    DNG and its default render, copied), with a manifest of sizes and SHA-256."""
    import hashlib
    import shutil

    import day2night
    from conftest import FIXTURES
    from day2night.png import write_png
    from day2night.train.targets import srgb8

    day = day2night.read_dng(str(FIXTURES / "day.dng"))
    t, l = day.meta["active_area"][:2]
    meta = {k: v for k, v in day.meta.items() if v is not None}
    meta.update(active_area=None, default_crop=None, width=16, height=16)
    raw = day2night.Raw.from_array(np.ascontiguousarray(day.data[t:t + 16, l:l + 16]), meta,
                                   name="s")
    (root / "src").mkdir(parents=True)
    dng, png = root / "src" / "s.dng", root / "src" / "s.png"
    day2night.write_dng(raw, str(dng))
    write_png(png, srgb8(day2night.render(raw)))
    lines = []
    for j in range(n):
        sid = "%03d" % j
        outs = []
        for kind, src, rel in (("clean_raw", dng, f"real/clean_raw/{sid}.dng"),
                               ("target", png, f"real/target/{sid}.png")):
            (root / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(src, root / rel)
            data = (root / rel).read_bytes()
            outs.append({"kind": kind, "path": rel, "bytes": len(data),
                         "sha256": hashlib.sha256(data).hexdigest()})
        lines.append(json.dumps({"kind": "real", "scene": sid, "status": "ok", "outputs": outs,
                                 "stages": ["clean_raw_png", "write_clean_raw",
                                            "copy_target_png"]}))
    (root / "manifest.jsonl").write_text("\n".join(lines) + "\n")
    days = root / "days"
    days.mkdir()
    for k in range(3):
        shutil.copy(dng, days / f"day{k}.dng")
    return root, days


def experiment(day, real, out, **options):
    """A runner.Experiment of these options (config.ExperimentConfig's fields)."""
    from day2night.experiment.config import ExperimentConfig
    from day2night.experiment.runner import Experiment

    return Experiment(ExperimentConfig(day=str(day), real=str(real), output=str(out),
                                       **options))


def test_folds_file_writes_the_release_lists_and_the_options_are_recorded(tmp_path):
    need_torch()
    from day2night.experiment.runner import ExperimentError

    real, days = tiny_real_set(tmp_path / "real", 105)
    lists = release_lists()
    k = tmp_path / "k_fold_indices_saved.p"
    k.write_bytes(pickle.dumps(lists))
    run = tmp_path / "run"
    exp = experiment(days, real, run, task="clean", epochs=1, width=4, rows=["mix5"],
                     protocol="release", folds_file=k)
    exp.prepare()
    saved = json.loads((run / "folds.json").read_text())
    assert [[int(s) for s in sp[part]] for sp in saved["splits"]
            for part in ("train", "val", "test")] == \
        [[int(j) for j in lists[key][i]] for i in range(3) for key in release_folds.KEYS]
    cfg = json.loads((run / "config.json").read_text())
    assert (cfg["protocol"], cfg["targets"], cfg["noise"], cfg["synth_iso"], cfg["folds"]) == \
        ("release", "release", "release", "release", 3)
    assert cfg["folds_sha256"] == __import__("hashlib").sha256(k.read_bytes()).hexdigest()
    # the synthetic slots' ISOs are the release-style draw per day image
    isos = protocol.release_isos(["day0.dng", "day1.dng", "day2.dng"], 0)
    mixes = json.loads((run / "mixes.json").read_text())
    synth = [s for s in mixes["mix5"][0] if s["kind"] == "synthetic"]
    assert synth and all(s["iso"] == isos[s["id"]] for s in synth)
    # a rerun with another option is refused before anything is written
    with pytest.raises(ExperimentError, match="targets = 'release', not 'day2night'"):
        experiment(days, real, run, task="clean", epochs=1, width=4, rows=["mix5"],
                   protocol="release", folds_file=k, targets="day2night").prepare()
    with pytest.raises(ExperimentError, match="folds_sha256"):
        k.write_bytes(pickle.dumps(release_lists(val=11)))
        experiment(days, real, run, task="clean", epochs=1, width=4, rows=["mix5"],
                   protocol="release", folds_file=k).prepare()
    with pytest.raises(protocol.ProtocolError, match="--folds 4: the fold file"):
        experiment(days, real, tmp_path / "run2", folds=4, folds_file=k)


def test_the_targets_default_to_the_release_for_copied_pngs(tmp_path):
    real, days = tiny_real_set(tmp_path / "real", 6)
    c = experiment(days, real, tmp_path / "run", task="clean").config
    assert (c.targets, c.noise, c.synth_iso, c.folds) == \
        ("release", "day2night", "alternate", 3)
    c = experiment(days, real, tmp_path / "run", task="clean", targets="day2night").config
    assert c.targets == "day2night"


def processed_tree(cli, root):
    """The release's processed night_real/ tree made from the tests' stand-in bursts
    (experiment_mini): clean_raw/NNN.png (the truncated mean of the ISO 50 frames, 16-bit),
    clean/NNN.png (that mean rendered by the release's ISP), dng/iso_*/NNN.dng."""
    import shutil

    cv2 = pytest.importorskip("cv2")
    import day2night
    import experiment_mini as em
    from conftest import FIXTURES
    from day2night.png import write_png
    from day2night.train.targets import render_target

    days = em.day_dir(root / "days", FIXTURES / "day.dng")
    release, _ = em.bursts(cli, root / "captures", FIXTURES / "day.dng", frames=2)
    tree = root / "night_real"
    for d in ("clean_raw", "clean", "dng/iso_50", "dng/iso_1600", "dng/iso_3200"):
        (tree / d).mkdir(parents=True)
    for i, scene in enumerate(sorted(p.name for p in release.iterdir())):
        sid = "%03d" % i
        frames = {iso: sorted((release / scene).glob(f"RAW_0_00{iso:04d}_*.dng"))
                  for iso in (50, 1600, 3200)}
        for iso, fs in frames.items():
            shutil.copy(fs[0], tree / "dng" / f"iso_{iso}" / f"{sid}.dng")
        raws = [day2night.read_dng(str(f)) for f in frames[50]]
        mean = (sum(r.data.astype(np.uint32) for r in raws) // len(raws)).astype(np.uint16)
        cv2.imwrite(str(tree / "clean_raw" / f"{sid}.png"), mean)
        meta = {k: v for k, v in raws[0].meta.items() if v is not None}
        clean = day2night.Raw.from_array(mean, meta, name=sid)
        write_png(tree / "clean" / f"{sid}.png", render_target(clean, isp="release"))
    return days, tree


def test_the_release_protocol_end_to_end(tmp_path, cli):
    """real-pairs copies the release's PNGs from a processed tree; the experiment then runs
    with the release's targets (synthetic ones rendered by its ISP), its fold lists and its
    noise, from one command."""
    import experiment_mini as em

    from day2night.experiment import pairs

    days, tree = processed_tree(cli, tmp_path)
    real = tmp_path / "real"
    cli("real-pairs", tree, "-o", real, "-q")
    assert protocol.real_target_isp(real) == "release"
    lists = {"train_index_all": [[2, 3, 5], [0, 1, 5], [0, 1, 3]],
             "val_index_all": [[4], [4], [2]],
             "test_index_all": [[0, 1], [2, 3], [4, 5]]}
    (tmp_path / "folds.json").write_text(json.dumps(lists))
    run = tmp_path / "run"
    env = dict(os.environ, OMP_NUM_THREADS="1")
    em.run_experiment(run, days, real, "--epochs", 1, "--width", 4, "--task", "clean",
                      "--rows", "ours", "supervised", "--protocol", "release",
                      "--folds-file", tmp_path / "folds.json", env=env)
    cfg = json.loads((run / "config.json").read_text())
    assert (cfg["targets"], cfg["noise"], cfg["synth_iso"]) == ("release",) * 3
    saved = json.loads((run / "folds.json").read_text())
    assert [sp["test"] for sp in saved["splits"]] == [["000", "001"], ["002", "003"],
                                                       ["004", "005"]]
    # a real target is the release's PNG; a synthetic one the release ISP's render
    assert np.array_equal(np.load(run / "data" / "real" / "000.y.npy"),
                          pairs.read_png(tree / "clean" / "000.png"))
    y = np.load(run / "data" / "synth-local" / "day_00.y.npy")
    _, want = pairs.synth_pairs(days / "day_00.dng", "local", 0, isos=(),
                                targets="release")["clean"]
    assert np.array_equal(y, want)
    _, theirs = pairs.synth_pairs(days / "day_00.dng", "local", 0, isos=())["clean"]
    assert not np.array_equal(y, theirs)  # day2night's ISP renders another target
    assert (run / "table.json").is_file()


def test_real_pairs_isp_release_targets_make_release_the_default(tmp_path, cli):
    """real-pairs --isp release renders the bursts' targets with the release's ISP: the
    experiment's --targets then defaults to release, and the pairs line up."""
    import experiment_mini as em
    from conftest import FIXTURES

    from day2night.experiment import pairs, realset

    release, _ = em.bursts(cli, tmp_path / "captures", FIXTURES / "day.dng", frames=2)
    real = tmp_path / "real"
    cli("real-pairs", release, "-o", real, "--isp", "release", "-q")
    assert protocol.real_target_isp(real) == "release"
    scene = realset.read_real(real)[0]
    x, y = pairs.real_pair(scene, None, targets="release", source="release")
    from test_experiment_orientation import correlations, edges

    r = correlations(edges(x), edges(np.asarray(y, np.float64) / 255))
    assert max(r, key=r.get) == (0, 0) and r[0, 0] > 0.8, r[0, 0]
    plain = tmp_path / "plain"
    cli("real-pairs", release, "-o", plain, "-q")
    assert protocol.real_target_isp(plain) == "day2night"


def test_resume_reads_a_config_from_before_the_protocol_options(tmp_path):
    """A run folder whose config.json predates --protocol/--targets/--noise/--synth-iso/
    --folds-file resumes under the options that reproduce what it ran with, and only those."""
    import json

    from day2night.experiment import config, prepare, protocol

    old = {"day": "d", "real": "r", "task": "clean", "epochs": 2, "seed": 0, "folds": 3,
           "width": 8, "device": "cpu", "rows": ["ours"]}
    (tmp_path / "config.json").write_text(json.dumps(old))
    c, _ = config.resolve(config.ExperimentConfig(day="d", real=str(tmp_path), output="o"))
    new = dict(old, **{k: v for k, v in c.record().items() if k in protocol.LEGACY_CONFIG})
    prepare.check_config(tmp_path, new)  # accepted
    for key, value in [("noise", "release"), ("synth_iso", "release"),
                       ("targets", "release"), ("protocol", "release")]:
        with pytest.raises(prepare.ExperimentError, match=f"{key} = "):
            prepare.check_config(tmp_path, dict(new, **{key: value}))


def test_the_fresh_row_stays_out_of_a_release_table():
    """FreshPatches synthesizes with day2night's ISP and noise: under release targets or
    noise it would bring a second ISP into the table, so it is left out by default and
    refused when named; with day2night's targets and noise it runs."""
    from day2night.experiment import rows

    every = rows.select([])
    ours = ("day2night", "day2night")
    assert [r.id for r in protocol.fresh_rows(every, *ours, False)] == [r.id for r in every]
    assert "fresh" in [r.id for r in every]
    for targets_noise in (("release", "day2night"), ("day2night", "release")):
        kept = [r.id for r in protocol.fresh_rows(every, *targets_noise, False)]
        assert kept == [r.id for r in every if r.id != "fresh"]
        with pytest.raises(protocol.ProtocolError, match="--rows fresh"):
            protocol.fresh_rows(rows.select(["ours", "fresh"]), *targets_noise, True)
        named = protocol.fresh_rows(rows.select(["ours"]), *targets_noise, True)
        assert [r.id for r in named] == ["ours"]
