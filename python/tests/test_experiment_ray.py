"""The experiment's units on Ray (issue 46): a run with ``--ray`` (a local Ray instance on
CPU) gives the serial run's table.json and every unit's scores.json, byte for byte, with
``--seeds 2`` and a per-fold row; a worker killed mid-unit is retried by Ray and the unit
resumes from its checkpoint to the same table; a unit that fails for its own reason fails
the run after the others are kept, naming it and the rerun; two Ray nodes started on this
machine run one experiment, units on both; ``--plan`` prints the units and writes nothing.

Needs torch and ``ray`` (scripts/test.sh installs it from python/tests/requirements-ray.txt
and sets D2N_REQUIRE_RAY=1, which makes a missing ray a failure instead of a skip)."""

import json
import os
import pathlib
import shutil
import signal
import socket
import subprocess
import sys
import tempfile

import pytest

from conftest import need_torch

need_torch(module=True)  # skips (or fails) the module the trainer's tests' way
try:
    import ray  # noqa: F401
except ImportError as e:
    if os.environ.get("D2N_REQUIRE_RAY") == "1":
        pytest.fail(f"D2N_REQUIRE_RAY=1 but ray cannot be imported: {e}", pytrace=False)
    pytest.skip(os.environ.get("D2N_RAY_SKIP_REASON")
                or f"ray is not installed ({e}); scripts/test.sh installs it",
                allow_module_level=True)

import experiment_mini as mini  # noqa: E402
from conftest import FIXTURES  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
# the smallest run with a per-fold row (supervised: 3 folds) and two seeds: 10 units
ARGS = ["--epochs", 2, "--width", 4, "--rows", "day", "supervised", "--task", "clean",
        "--seeds", 2, "--seed", 7]


def env(**extra):
    e = dict(os.environ, RAY_USAGE_STATS_ENABLED="0", **extra)
    e.setdefault("OMP_NUM_THREADS", "1")  # the same sums in every process (one thread)
    e.pop("RAY_ADDRESS", None)
    pysrc = str(pathlib.Path(__import__("day2night").__file__).resolve().parents[1])
    e["PYTHONPATH"] = os.pathsep.join(p for p in (pysrc, e.get("PYTHONPATH")) if p)
    return e


@pytest.fixture(scope="module")
def mini_set(tmp_path_factory, cli):
    root = tmp_path_factory.mktemp("mini_ray")
    day = mini.day_dir(root / "days", FIXTURES / "day.dng")
    release, _ = mini.bursts(cli, root / "captures", FIXTURES / "day.dng")
    real = root / "real"
    cli("real-pairs", release, "-o", real)
    return {"root": root, "day": day, "real": real}


def run(mini_set, name, *extra, check=True, **kw):
    out = mini_set["root"] / name
    r = mini.run_experiment(out, mini_set["day"], mini_set["real"], *ARGS, *extra,
                            env=env(**kw), check=check)
    return out, r


@pytest.fixture(scope="module")
def serial(mini_set):
    return run(mini_set, "serial")[0]


def unit_scores(out):
    return {p.relative_to(out).as_posix(): p.read_bytes()
            for p in sorted(out.rglob("scores.json"))}


def assert_same_results(a, b):
    assert (a / "table.json").read_bytes() == (b / "table.json").read_bytes()
    assert (a / "table.md").read_bytes() == (b / "table.md").read_bytes()
    sa, sb = unit_scores(a), unit_scores(b)
    assert len(sa) == 10 and sa == sb


def nodes(out):
    return [json.loads(p.read_text()) for p in sorted(out.rglob("node.json"))]


def test_ray_run_equals_the_serial_run(serial, mini_set):
    out, r = run(mini_set, "ray", "--ray")
    assert_same_results(serial, out)
    ran = nodes(out)
    assert len(ran) == 10 and all(n["node_id"] and n["ip"] for n in ran)
    assert "10/10 units:" in r.stderr and "ETA" in r.stderr
    log = (out / "log.txt").read_text()
    assert "10/10 units:" in log
    assert not (out / "driver.lock").exists()
    # a rerun skips every unit and writes the same table
    out2, r = run(mini_set, "ray", "--ray")
    assert "was done already" in r.stderr
    assert_same_results(serial, out2)


def test_a_killed_worker_is_retried_and_resumes(serial, mini_set, tmp_path):
    marker = tmp_path / "killed"
    out = mini_set["root"] / "ray_killed"
    cmd = [sys.executable, str(HERE / "ray_hooks.py"), "--day", str(mini_set["day"]),
           "--real", str(mini_set["real"]), "-o", str(out), *map(str, ARGS), "--ray"]
    r = subprocess.run(cmd, capture_output=True, text=True,
                       env=env(D2N_TEST_KILL_EPOCH="1", D2N_TEST_MARKER=str(marker)))
    assert r.returncode == 0, r.stderr[-4000:]
    assert marker.is_file(), "no worker was killed"
    assert_same_results(serial, out)


def test_a_failing_unit_fails_the_run_after_the_others(serial, mini_set):
    out = mini_set["root"] / "ray_failing"
    cmd = [sys.executable, str(HERE / "ray_hooks.py"), "--day", str(mini_set["day"]),
           "--real", str(mini_set["real"]), "-o", str(out), *map(str, ARGS), "--ray"]
    r = subprocess.run(cmd, capture_output=True, text=True,
                       env=env(D2N_TEST_FAIL_UNIT="clean/supervised/1"))
    assert r.returncode == 1, r.stderr[-4000:]
    # the driver's last line (Ray may print its own after it, when ray_hooks.py shuts it down)
    last = [ln for ln in r.stderr.splitlines() if ln.startswith("day2night.experiment:")][-1]
    assert last.startswith("day2night.experiment: error: unit clean/supervised/1 failed: "
                           "ValueError: injected failure of unit clean/supervised/1"), last
    assert "--restart-unit clean/supervised/1" in last and "the other 9 unit(s)" in last
    assert len(unit_scores(out)) == 9 and not (out / "table.json").exists()
    assert not (out / "driver.lock").exists()
    # the same command, the fault gone: only that unit runs, and the table is the serial one
    out, r = run(mini_set, "ray_failing", "--ray")
    assert r.stderr.count("was done already") == 9
    assert_same_results(serial, out)


def test_a_killed_driver_is_resumed_by_the_same_command(serial, mini_set):
    out = mini_set["root"] / "ray_driver_killed"
    cmd = [sys.executable, "-m", "day2night.experiment", "--day", str(mini_set["day"]),
           "--real", str(mini_set["real"]), "-o", str(out), *map(str, ARGS), "--ray"]
    # its own session: the kill takes the driver and the local Ray instance it started
    p = subprocess.Popen(cmd, env=env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         text=True, start_new_session=True)
    for line in p.stderr:  # killed once the first unit is done: the others are in flight
        if "units: " in line and " done on node " in line:
            os.killpg(p.pid, signal.SIGKILL)
            break
    p.wait()
    p.stderr.close()
    assert p.returncode == -signal.SIGKILL
    assert (out / "driver.lock").is_file() and not (out / "table.json").exists()
    done = len(unit_scores(out))
    assert 1 <= done < 10
    _, r = run(mini_set, "ray_driver_killed", "--ray")
    assert "taking over the stale lock" in r.stderr
    assert r.stderr.count("was done already") >= done
    assert_same_results(serial, out)


def test_plan_prints_the_units_and_writes_nothing(mini_set):
    out = mini_set["root"] / "plan"
    r = mini.run_experiment(out, mini_set["day"], mini_set["real"], *ARGS, "--plan",
                            env=env())
    assert not out.exists()
    lines = r.stdout.splitlines()
    assert lines[0].split() == ["unit", "patch-steps", "GPU-hours"]
    units = [ln.split()[0] for ln in lines[1:11]]
    assert sorted(units) == sorted(
        [f"{p}clean/{r}/{f}" for p in ("", "seed-8/")
         for r, f in [("untrained", "all"), ("day", "all"), ("supervised", "0"),
                      ("supervised", "1"), ("supervised", "2")]])
    steps = {ln.split()[0]: int(ln.split()[1].replace(",", "")) for ln in lines[1:11]}
    assert steps["clean/untrained/all"] == 0 and steps["clean/day/all"] > 0
    assert all(v == steps[k.replace("seed-8/", "")] for k, v in steps.items())
    assert "10 units (0 done)" in lines[11] and "10 TFLOP/s" in lines[11]
    assert "each unit asks for 0 GPU and 1 CPU" in lines[12]


# the nodes, the driver and no one else: no token (~/.ray/auth_token is shared by every Ray
# user of this account, and another one may write it meanwhile)
NO_TOKEN = {"RAY_AUTH_MODE": "disabled"}


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _ray_start(args, tmp):
    exe = shutil.which("ray") or str(pathlib.Path(sys.executable).with_name("ray"))
    ports = ["--node-manager-port", _free_port(), "--object-manager-port", _free_port(),
             "--dashboard-agent-listen-port", _free_port(), "--dashboard-agent-grpc-port",
             _free_port(), "--metrics-export-port", _free_port(), "--runtime-env-agent-port",
             _free_port()]
    cmd = [exe, "start", "--num-cpus", "1", "--num-gpus", "0", "--temp-dir", str(tmp),
           "--disable-usage-stats", *map(str, ports), *map(str, args)]
    r = subprocess.run(cmd, capture_output=True, text=True, env=env(**NO_TOKEN), timeout=300)
    assert r.returncode == 0, r.stderr[-3000:] + r.stdout[-3000:]


def _stop_nodes(tmps):
    """Kill the processes of the nodes this test started (those whose command line names
    one of its temp folders), by pid."""
    import signal

    for p in pathlib.Path("/proc").iterdir():
        if not p.name.isdigit():
            continue
        try:
            cmdline = (p / "cmdline").read_bytes().decode("utf-8", "replace")
        except OSError:
            continue
        if any(str(t) in cmdline for t in tmps):
            try:
                os.kill(int(p.name), signal.SIGKILL)
            except ProcessLookupError:
                pass


def test_two_nodes_run_one_experiment(serial, mini_set):
    tmps = [pathlib.Path(tempfile.mkdtemp(prefix="d2n-ray-", dir="/tmp")) for _ in range(2)]
    port = _free_port()
    try:
        _ray_start(["--head", "--port", port, "--include-dashboard", "false",
                    "--ray-client-server-port", _free_port(), "--node-ip-address",
                    "127.0.0.1"], tmps[0])
        _ray_start(["--address", f"127.0.0.1:{port}", "--node-ip-address", "127.0.0.1"],
                   tmps[1])
        out, r = run(mini_set, "ray_two_nodes", "--ray", f"127.0.0.1:{port}", **NO_TOKEN)
        assert "Ray: 2 node(s), 2 CPU" in r.stderr, r.stderr[-3000:]
        assert_same_results(serial, out)
        assert len({n["node_id"] for n in nodes(out)}) == 2, nodes(out)
    finally:
        _stop_nodes(tmps)
        for t in tmps:
            shutil.rmtree(t, ignore_errors=True)
