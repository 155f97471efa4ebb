"""Helpers of the dataset tests (test_dataset_units.py, test_ray.py): a small day folder of
fixtures and the comparison of two dataset trees."""

import pathlib
import shutil

import pytest

FIXTURES = pathlib.Path(__file__).resolve().parents[2] / "fixtures"


def tree(root):
    """Every file under root (hidden ones too): relative path -> bytes; the manifest as the
    set of its lines."""
    out = {}
    for p in sorted(root.rglob("*")):
        if p.is_file():
            rel = p.relative_to(root).as_posix()
            data = p.read_bytes()
            out[rel] = frozenset(data.splitlines()) if rel.endswith(".jsonl") else data
    return out


def assert_same_tree(a, b):
    ta, tb = tree(a), tree(b)
    assert sorted(ta) == sorted(tb), f"file names differ: {sorted(set(ta) ^ set(tb))}"
    for k in ta:
        assert ta[k] == tb[k], f"{k} differs"


@pytest.fixture()
def days(tmp_path):
    d = tmp_path / "days"
    (d / "sub").mkdir(parents=True)
    shutil.copy(FIXTURES / "day.dng", d / "a.dng")
    shutil.copy(FIXTURES / "bggr_14bit_packed_le_subifd_black2x2.dng", d / "b.dng")
    shutil.copy(FIXTURES / "grbg_12bit_packed_be_strips.dng", d / "sub" / "c.dng")
    return d
