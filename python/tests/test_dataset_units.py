"""dataset_units / write_unit / write_manifest: `day2night dataset` as independent units.

Units written in any order (here: reversed, in this process), then the manifest, give the
tree the command line writes with the same options, byte for byte (the Ray example runs
the same three calls on a cluster: test_ray.py)."""

import json
import warnings

import pytest

import day2night
from dataset_trees import assert_same_tree, days  # noqa: F401 (a fixture)


def run_units(days, out, unit_kw, options, order=reversed):
    units = day2night.dataset_units(days, out, **unit_kw)
    records = [day2night.write_unit(u, out, **options) for u in order(units)]
    day2night.write_manifest(records, out, shard=unit_kw.get("shard"))
    return units, records


def test_units_equal_the_cli_tree(cli, days, tmp_path):
    a, b = tmp_path / "cli", tmp_path / "units"
    cli("dataset", days, "-o", a, "--variants", "2", "--val", "1", "--seed", "7",
        "--iso", "800,3200", "--target", "both", "--input-exr", "--compression", "ljpeg",
        "--exr-compression", "piz", "--quiet")
    units, records = run_units(days, b, dict(variants=2, val=1, seed=7),
                               dict(iso="800,3200", target="both", input_exr=True,
                                    compression="ljpeg", exr_compression="piz"))
    assert [u["id"] for u in units] == ["a_v1", "a_v2", "b_v1", "b_v2", "sub__c_v1", "sub__c_v2"]
    assert [u["split"] for u in units] == ["train"] * 4 + ["val"] * 2
    assert all(u["previous"] is None for u in units)
    assert all(r["status"] == "ok" for r in records)
    assert_same_tree(a, b)


def test_defaults_fraction_split_and_shards(cli, days, tmp_path):
    a = tmp_path / "cli"
    cli("dataset", days, "-o", a, "--val-fraction", "0.5", "--seed", "3", "--quiet")
    b = tmp_path / "units"
    # Two shards into one folder, each with its own manifest; then the unsharded manifest.
    records = []
    for i in range(2):
        _, r = run_units(days, b, dict(val_fraction=0.5, seed=3, shard=f"{i}/2"), {},
                         order=list)
        records += r
    assert (b / "manifest.shard-0-of-2.jsonl").is_file()
    for m in b.glob("manifest.shard-*"):
        m.unlink()
    day2night.write_manifest(records, b)
    assert_same_tree(a, b)
    # Up to date: every unit carries its record and is skipped.
    units = day2night.dataset_units(days, b, val_fraction=0.5, seed=3)
    assert all(json.loads(u["previous"])["status"] == "ok" for u in units)
    rec, why = day2night.write_unit(units[0], b, reason=True)
    assert why is None and rec == json.loads(units[0]["previous"])


def test_resume_after_a_partial_run(cli, days, tmp_path):
    a, b = tmp_path / "cli", tmp_path / "units"
    cli("dataset", days, "-o", a, "--variants", "2", "--quiet")
    units = day2night.dataset_units(days, b, variants=2)
    for u in units[:3]:  # "killed" after three units: no manifest
        day2night.write_unit(u, b)
    tmp = b / "train" / "noisy_raw" / ".b_v2_iso1600.dng.tmp-99999"
    tmp.parent.mkdir(parents=True, exist_ok=True)
    tmp.write_bytes(b"half written")
    units = day2night.dataset_units(days, b, variants=2)
    assert not tmp.exists()
    outcome = [day2night.write_unit(u, b, reason=True) for u in units]
    assert [why for _, why in outcome] == [None] * 3 + ["new"] * 3
    day2night.write_manifest([r for r, _ in outcome], b)
    assert_same_tree(a, b)
    # An output deleted after the manifest: only its unit is recomputed.
    (b / "train" / "target" / "a_v2.exr").unlink()
    units = day2night.dataset_units(days, b, variants=2)
    outcome = [day2night.write_unit(u, b, reason=True) for u in units]
    assert [why for _, why in outcome].count(None) == 5
    assert outcome[1][1] == "outputs missing or altered"
    day2night.write_manifest([r for r, _ in outcome], b)
    assert_same_tree(a, b)


def test_errors(days, tmp_path):
    out = tmp_path / "o"
    units = day2night.dataset_units(days)
    with pytest.raises(ValueError, match="unknown option"):
        day2night.write_unit(units[0], out, seed=1)
    with pytest.raises(ValueError, match="iso"):
        day2night.write_unit(units[0], out, iso="0")
    with pytest.raises(ValueError, match="target"):
        day2night.write_unit(units[0], out, target="tiff")
    with pytest.raises(ValueError, match="val"):
        day2night.dataset_units(days, val=9)
    with pytest.raises(ValueError, match="not both"):
        day2night.dataset_units(days, val=1, val_fraction=0.5)
    with pytest.raises(ValueError, match="shard"):
        day2night.dataset_units(days, shard="2/2")
    with pytest.raises(ValueError, match="not a dataset"):
        (tmp_path / "foreign").mkdir()
        (tmp_path / "foreign" / "x.txt").write_text("mine")
        day2night.dataset_units(days, tmp_path / "foreign")
    bad = dict(units[0], id="other")
    with pytest.raises(ValueError, match="id"):
        day2night.write_unit(bad, out)
    with pytest.raises(ValueError, match="record"):
        day2night.write_manifest([{"input": "a.dng"}], out)
    # A bad input is a failed record, as `dataset` records it.
    (days / "z.dng").write_bytes(b"not a dng")
    z = [u for u in day2night.dataset_units(days) if u["input"] == "z.dng"][0]
    rec = day2night.write_unit(z, out)
    assert rec["status"] == "failed" and "z.dng" in rec["error"]


def with_bad_noise_profile(src, dst):
    """A copy of a DNG whose NoiseProfile is invalid (S < 0): the reader ignores it with a
    warning that `dataset`'s loader prints once per decode, so the warnings count decodes."""
    import struct

    import tifffile
    with tifffile.TiffFile(src) as t:
        tag = t.pages[0].tags["NoiseProfile"]
        order, offset = t.byteorder, tag.valueoffset
    data = bytearray(src.read_bytes())
    struct.pack_into(order + "d", data, offset, -1.0)
    dst.write_bytes(bytes(data))


def profile_warnings(call):
    """Run call(); the NoiseProfileInvalidWarning raised (one per decode), and its result."""
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        out = call()
    got = [w for w in rec if issubclass(w.category, day2night.NoiseProfileInvalidWarning)]
    assert all(w.message.code == "noise-profile-invalid" and "NoiseProfile pair 0" in str(w.message)
               for w in got), got
    return len(got), out


def test_write_units_decodes_each_input_once(cli, tmp_path, capfd):
    from dataset_trees import FIXTURES
    days = tmp_path / "days"
    days.mkdir()
    for name in ("a", "b"):
        with_bad_noise_profile(FIXTURES / "day.dng", days / f"{name}.dng")
    kw = dict(variants=3, val=1, seed=11)
    opts = dict(iso="800", target="exr")
    a, b, c = tmp_path / "cli", tmp_path / "one_by_one", tmp_path / "grouped"
    capfd.readouterr()
    cli("dataset", days, "-o", a, "--variants", "3", "--val", "1", "--seed", "11", "--iso", "800",
        "--quiet")
    units = day2night.dataset_units(days, b, **kw)
    assert [len(g) for g in day2night.group_units(units)] == [3, 3]
    assert [u["id"] for g in day2night.group_units(units) for u in g] == [u["id"] for u in units]
    one_by_one, recs = profile_warnings(lambda: [day2night.write_unit(u, b, **opts) for u in units])
    day2night.write_manifest(recs, b)
    units = day2night.dataset_units(days, c, **kw)
    grouped, records = profile_warnings(
        lambda: [r for g in day2night.group_units(units) for r in day2night.write_units(g, c, **opts)])
    day2night.write_manifest(records, c)
    # One decode per unit, against one per input (as `dataset`); the same bytes.
    assert (one_by_one, grouped) == (6, 2)
    assert_same_tree(a, b)
    assert_same_tree(a, c)
    # Up to date: every unit skipped, nothing decoded. Units of both inputs in one call
    # (any order) are grouped by input; one output deleted: one decode, one unit redone.
    (c / "train" / "target" / "a_v2.exr").unlink()
    units = day2night.dataset_units(days, c, **kw)
    n, done = profile_warnings(
        lambda: day2night.write_units(list(reversed(units)), c, reason=True, **opts))
    assert n == 1
    assert [why for _, why in done] == [None] * 4 + ["outputs missing or altered", None]
    assert [r["variant"] for r, _ in done] == [3, 2, 1, 3, 2, 1]
    day2night.write_manifest([r for r, _ in done], c)
    assert_same_tree(a, c)
    assert day2night.write_units([], c) == []
    with pytest.raises(ValueError, match=r"units\[1\]: unit has no \"path\""):
        day2night.write_units([units[0], {"input": "a.dng"}], c)
