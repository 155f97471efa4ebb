"""A tampered RUN/data cache is refused naming the file (issue 42 item 11): a header whose
gamma id is not the one a run writes, a CFA pattern that is not a Bayer pattern, a code past
the table, and an input of the first cache format (``.x.npy``) holding NaN or inf, which
would be migrated and trained on."""

import io

import numpy as np
import pytest

from day2night.experiment import pairs, runfolder
from day2night.train import cache, preprocess


def cfa_input(h=24, w=32, seed=0):
    """A network input on the release's gamma table whose codes are a bilinear demosaic of a
    Bayer mosaic: what a run stores as CFA14."""
    mosaic = np.random.default_rng(seed).integers(0, 16384, (h, w), dtype=np.uint16)
    codes = preprocess.demosaic_bilinear(mosaic, cache.PATTERNS[0])
    return preprocess._table(preprocess.GAMMA)[codes]


def stored_pair(folder, name="000"):
    x = cfa_input()
    y = np.zeros(x.shape, np.uint8)
    xp, yp = pairs.cached(folder, {"clean": name}, lambda: {"clean": (x, y)})["clean"]
    return xp, yp, x


def rewrite(path, edit):
    a = np.array(np.load(path, allow_pickle=False))
    edit(a)
    buf = io.BytesIO()
    np.save(buf, a, allow_pickle=False)
    path.write_bytes(buf.getvalue())


def test_a_run_stores_cfa14_on_gamma_id_1_and_its_checks_pass(tmp_path):
    xp, yp, x = stored_pair(tmp_path / "data" / "real")
    head = cache.info(np.load(xp))
    assert (head["encoding"], head["gamma_id"], pairs.RUN_GAMMA_ID) == (cache.CFA14, 1, 1)
    assert pairs.check_cached(xp, yp) == x.shape[:2]
    runfolder.check_data(tmp_path)
    assert np.array_equal(pairs.load(xp), x)


def test_a_changed_gamma_id_is_refused(tmp_path):
    xp, yp, _ = stored_pair(tmp_path / "data" / "real")
    rewrite(xp, lambda a: a.__setitem__(8, 0))
    with pytest.raises(ValueError, match=rf"{xp}: damaged cached array: a cfa14 store with "
                       "gamma id 0; a run writes"):
        pairs.check_cached(xp, yp)
    with pytest.raises(runfolder.RunFolderError, match=rf"{xp}: .*gamma id 0.*delete it"):
        runfolder.check_data(tmp_path)


@pytest.mark.parametrize("at, value, match", [
    (9, 7, r"CFA pattern \(7, 1, 1, 2\) in its header is not a 2x2 Bayer pattern"),
    (10, 0, r"CFA pattern \(0, 0, 1, 2\)"),
    (14, 1, "header values 13..15 are not 0"),
])
def test_a_damaged_header_is_refused_naming_the_file(tmp_path, at, value, match):
    xp, yp, _ = stored_pair(tmp_path / "data" / "real")
    rewrite(xp, lambda a: a.__setitem__(at, value))
    with pytest.raises(cache.CacheFormatError, match=rf"{xp}: {match}"):
        pairs.load(xp)
    with pytest.raises(runfolder.RunFolderError, match=rf"{xp}: damaged cached array .*{match}"):
        runfolder.check_data(tmp_path)


def test_a_code_past_the_table_is_refused_naming_the_file(tmp_path):
    xp, _, _ = stored_pair(tmp_path)
    rewrite(xp, lambda a: a.__setitem__(cache.HEADER + 10 * 32 + 10, 20000))
    with pytest.raises(cache.CacheFormatError, match=rf"{xp}: code \d+ past the 16384-entry"):
        pairs.load(xp)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -1.0, 2.0])
def test_an_old_input_with_values_a_run_never_writes_is_not_migrated(tmp_path, bad):
    folder = tmp_path / "data" / "real"
    folder.mkdir(parents=True)
    x = cfa_input()
    x[3, 4, 1] = bad
    np.save(folder / "000.x.npy", x)
    np.save(folder / "000.y.npy", np.zeros(x.shape, np.uint8))
    with pytest.raises(runfolder.RunFolderError,
                       match=r"000\.x\.npy: damaged cached array: values that are not finite"):
        runfolder.check_data(tmp_path)
    with pytest.raises(pairs.PairError, match=r"000\.x\.npy: an input of the first cache "
                       "format holding values that are not finite or outside"):
        pairs.cached(folder, {"clean": "000"}, lambda: pytest.fail("made again"))
    assert (folder / "000.x.npy").is_file() and not (folder / "000.in.npy").exists()
