"""One driver per run folder (issue 46, RUN/driver.lock, runlock.py): a second driver is
refused with one line naming the holder's host and pid (exit 2), a stale lock of a dead
process on this host is taken over with a warning, a lock of another host never is; and
``--ray`` without ray installed is one line, exit 2, before anything is read."""

import json
import os
import socket
import subprocess
import sys

import pytest

import experiment_mini as mini
from conftest import FIXTURES
from day2night.experiment import runlock

HOST = socket.gethostname()


def dead_pid():
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_a_second_acquire_is_refused_naming_the_holder(tmp_path):
    path = runlock.acquire(tmp_path / "run")
    assert json.loads(path.read_text()) == {"host": HOST, "pid": os.getpid()}
    with pytest.raises(runlock.RunFolderBusy) as e:
        runlock.acquire(tmp_path / "run")
    msg = str(e.value)
    assert f"(host {HOST}, pid {os.getpid()})" in msg and "\n" not in msg
    assert [p.name for p in (tmp_path / "run").iterdir()] == ["driver.lock"]  # no temp left
    runlock.release(path)
    assert not path.exists()
    runlock.release(runlock.acquire(tmp_path / "run"))  # free again


def test_a_stale_lock_is_taken_over_with_a_warning(tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    pid = dead_pid()
    (run / "driver.lock").write_text(json.dumps({"host": HOST, "pid": pid}))
    path = runlock.acquire(run)
    assert json.loads(path.read_text())["pid"] == os.getpid()
    err = capsys.readouterr().err
    assert f"taking over the stale lock {path} of host {HOST}, pid {pid}" in err
    runlock.release(path)


@pytest.mark.parametrize("text", [json.dumps({"host": "another-host", "pid": 1}), "garbage"])
def test_a_lock_of_another_host_or_unreadable_is_never_taken(tmp_path, text):
    run = tmp_path / "run"
    run.mkdir()
    (run / "driver.lock").write_text(text)
    with pytest.raises(runlock.RunFolderBusy) as e:
        runlock.acquire(run)
    assert str(run / "driver.lock") in str(e.value)
    if "another-host" in text:
        assert "(host another-host, pid 1)" in str(e.value)
    assert (run / "driver.lock").read_text() == text
    runlock.release(run / "driver.lock")  # not ours: left alone
    assert (run / "driver.lock").read_text() == text


def test_release_leaves_another_holders_lock(tmp_path):
    path = runlock.acquire(tmp_path)
    path.write_text(json.dumps({"host": HOST, "pid": 1}))
    runlock.release(path)
    assert path.exists()


def test_the_command_is_refused_while_another_driver_holds_the_folder(tmp_path, cli):
    # the lock is taken before the inputs' checks when the run folder exists: a folder
    # held by this (live) process refuses the command, and is left as it was
    day = mini.day_dir(tmp_path / "days", FIXTURES / "day.dng")
    release, _ = mini.bursts(cli, tmp_path / "captures", FIXTURES / "day.dng")
    cli("real-pairs", release, "-o", tmp_path / "real")
    out = tmp_path / "run"
    path = runlock.acquire(out)
    r = mini.run_experiment(out, day, tmp_path / "real", "--rows", "day", "--task", "clean",
                            "--epochs", 1, "--width", 4, check=False)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, r.stderr[-2000:]
    assert lines[-1] == (f"day2night.experiment: error: {out} is in use by another driver "
                         f"(host {HOST}, pid {os.getpid()}): wait for it, or if that driver "
                         f"is gone, delete {path} and rerun")
    assert json.loads(path.read_text())["pid"] == os.getpid()
    assert [p.name for p in out.iterdir()] == ["driver.lock"]
    runlock.release(path)


def test_ray_missing_is_one_line_exit_2(tmp_path):
    fake = tmp_path / "fake"
    (fake / "ray").mkdir(parents=True)
    (fake / "ray" / "__init__.py").write_text("raise ImportError('No module named ray')\n")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(fake), env.get("PYTHONPATH")) if p)
    r = subprocess.run([sys.executable, "-m", "day2night.experiment", "--day", str(tmp_path),
                        "--real", str(tmp_path), "-o", str(tmp_path / "run"), "--ray"],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip().splitlines() == [
        "day2night.experiment: error: --ray: ray cannot be imported (No module named ray); "
        "pip install 'ray[default]' (python/tests/requirements-ray.txt)"]
    assert not (tmp_path / "run").exists()
