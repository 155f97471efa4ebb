"""python/examples/ray_dataset.py on a local Ray cluster with 2 CPUs: its tree equals
`day2night dataset`'s with the same options (file names, bytes, manifest lines), and a run
killed midway then rerun completes the tree, skipping the units it had completed.

Needs `ray[data]` (scripts/test.sh installs it from python/tests/requirements-ray.txt where a
wheel exists, and then sets D2N_REQUIRE_RAY=1 so that a broken install fails instead of
skipping)."""

import fcntl
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import pytest

import day2night
from dataset_trees import assert_same_tree, days  # noqa: F401 (a fixture)

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "ray_dataset.py"
ARGS = ["--variants", "2", "--val", "1", "--seed", "7", "--iso", "800,3200", "--target", "both"]


@pytest.fixture(scope="module", autouse=True)
def ray_installed():
    try:
        import ray  # noqa: F401
        import ray.data  # noqa: F401
    except ImportError as e:
        if os.environ.get("D2N_REQUIRE_RAY") == "1":
            pytest.fail(f"D2N_REQUIRE_RAY=1 but ray cannot be imported: {e}")
        pytest.skip(os.environ.get("D2N_RAY_SKIP_REASON")
                    or f"ray[data] is not installed ({e}); scripts/test.sh installs it")


def example(day_dir, out, *extra):
    cmd = [sys.executable, str(EXAMPLE), str(day_dir), "-o", str(out), "--num-cpus", "2",
           "--quiet", *ARGS, *extra]
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0")
    env.pop("RAY_ADDRESS", None)  # a local cluster, whatever the environment says
    # Its own process group: a kill takes the local cluster's processes with it.
    return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)


def finish(p, timeout=600):
    out, err = p.communicate(timeout=timeout)
    assert p.returncode == 0, f"ray_dataset.py failed ({p.returncode}):\n{err[-4000:]}"
    return err


def summary(err):
    m = re.search(r"(\d+) units: (\d+) computed, (\d+) skipped", err)
    assert m, err[-2000:]
    return tuple(int(x) for x in m.groups())


def test_ray_tree_equals_the_cli_tree(cli, days, tmp_path):  # noqa: F811
    a, b = tmp_path / "cli", tmp_path / "ray"
    cli("dataset", days, "-o", a, "--quiet", *ARGS)
    err = finish(example(days, b))
    assert summary(err) == (6, 6, 0)
    assert_same_tree(a, b)
    # A rerun over the finished tree computes nothing and changes no byte.
    err = finish(example(days, b))
    assert summary(err) == (6, 0, 6)
    assert_same_tree(a, b)


def test_ray_killed_then_rerun_completes_the_tree(cli, days, tmp_path):  # noqa: F811
    a, b = tmp_path / "cli", tmp_path / "ray"
    cli("dataset", days, "-o", a, "--quiet", *ARGS)
    journal = b / ".day2night-units"
    # The last unit of an input is locked as another process writing it would (the lock
    # file of src/output/lock.rs's OutputSetLock, flock'ed): the run (--wait) completes the
    # units before it in its task, and maybe other tasks, then waits for it, so it cannot
    # finish before the kill, and no clock decides anything. --overwrite: the lock file
    # makes the new OUT non-empty.
    units = day2night.dataset_units(days, None, variants=2, val=1, seed=7)
    locked = day2night.group_units(units)[0][-1]["id"]
    b.mkdir()
    lock = open(b / f".{locked}.lock", "w")
    fcntl.flock(lock, fcntl.LOCK_EX)
    p = example(days, b, "--num-cpus", "1", "--wait", "--overwrite")
    # A unit's record in the journal: some unit is complete. (A poll, with no deadline:
    # the run cannot end while the lock is held, unless it fails.)
    while not (journal.is_dir() and any(journal.iterdir())):
        assert p.poll() is None, f"ray_dataset.py ended ({p.returncode}):\n{p.communicate()[1][-4000:]}"
        time.sleep(0.02)
    os.killpg(p.pid, signal.SIGKILL)
    p.communicate()
    lock.close()
    (b / f".{locked}.lock").unlink()
    done = len(list(journal.iterdir()))
    assert 1 <= done < 6 and not (b / "manifest.jsonl").exists()
    # What a kill can also leave: a temporary file of a unit being written.
    stale = b / "val" / "noisy_raw" / ".sub__c_v2_iso800.dng.tmp-99999"
    stale.parent.mkdir(parents=True, exist_ok=True)
    stale.write_bytes(b"half")
    err = finish(example(days, b))
    units, computed, skipped = summary(err)
    assert units == 6 and skipped >= done and computed == 6 - skipped
    assert_same_tree(a, b)


def test_webdataset_shards_hold_the_loader_items(days, tmp_path):  # noqa: F811
    import io
    import json
    import tarfile

    import numpy as np

    from day2night import NightPairs

    out = tmp_path / "wds"
    script = EXAMPLE.with_name("ray_webdataset.py")
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0")
    env.pop("RAY_ADDRESS", None)
    r = subprocess.run([sys.executable, str(script), str(days), "-o", str(out), "--num-cpus", "2",
                        "--crop", "16", "--iso", "800,3200", "--seed", "5", "--epoch", "2",
                        "--crops-per-image", "3", "--items-per-shard", "4", "--quiet"],
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-4000:]
    samples = {}
    for t in sorted(out.glob("*.tar")):
        with tarfile.open(t) as tar:
            for m in tar.getmembers():
                key, ext = m.name.split(".", 1)
                samples.setdefault(key, {})[ext] = tar.extractfile(m).read()
    ds = NightPairs(days, crop=16, isos=(800, 3200), seed=5, crops_per_image=3)
    ds.set_epoch(2)
    assert len(samples) == len(ds) == 6  # the two top-level files x 3 crops
    for key, s in samples.items():
        meta = json.loads(s["json"])
        assert key == f"{meta['name']}_e2_{meta['index']:08d}"
        item = ds[meta["index"]]
        assert (meta["iso"], meta["variant"], meta["name"]) == (item["iso"], item["variant"],
                                                                item["name"])
        for k in ("noisy", "clean", "target"):
            assert np.array_equal(np.load(io.BytesIO(s[f"{k}.npy"])), item[k]), (key, k)
