"""The units on Ray (``--ray [ADDRESS]``, docs/experiment.md "At the paper's scale").

Ray schedules, places and retries; this module only says what to run and collects what
comes back (no pool, queue or retry loop of its own):

1. the cached pairs, one Ray task per day image and mode (every network input of a
   synthesis) and per real scene and input, each written by its task (pairs.cached, atomic);
2. one Ray task per unit (task, row, fold, seed), longest first (cost.py), each asking for
   ``--num-gpus`` GPUs and ``--cpus-per-unit`` CPUs. A task runs ``Experiment.run_unit``,
   the serial run's code: the unit's folder is written by its task only, and a task that
   Ray retries after its worker or node died resumes from the unit's ``last.pt``;
3. the driver keeps the table, the report and the log, as the serial run does.

A unit that fails for a reason of its own (bad data, out of memory) is not retried: the
other units run to the end and are kept, then :class:`UnitsFailed` names it, its reason,
and how to run it again. ``ray`` is imported only here, and only when ``--ray`` is given."""

import copy
import importlib
import os
import pathlib
import socket
import time

import day2night

from . import cost, runfolder
from ..atomic import write_json
from .config import ExperimentError
from .prepare import log

#: Ray retries a unit whose worker process or node died this many times (each attempt
#: resumes from the unit's last checkpoint); an exception of the unit itself is not retried.
MAX_RETRIES = 3
#: Written by a unit's task in its folder: where it ran (node id, address, host, pid).
NODE_RECORD = "node.json"


class UnitsFailed(RuntimeError):
    """Units that failed for their own reasons, after every other unit finished."""


def import_ray():
    """The ``ray`` module, or an ExperimentError saying how to install it (exit 2)."""
    try:
        ray = importlib.import_module("ray")  # the optional dependency, only for --ray
    except ImportError as e:
        raise ExperimentError(f"--ray: ray cannot be imported ({e}); pip install "
                              "'ray[default]' (python/tests/requirements-ray.txt)") from None
    return ray


def resources(config):
    """(num_gpus, num_cpus) one unit asks Ray for."""
    gpus = config.num_gpus
    if gpus is None:
        gpus = 1.0 if config.device == "cuda" else 0.0
    cpus = config.cpus_per_unit
    if cpus is None:
        cpus = float(max(1, config.workers))
    return float(gpus), float(cpus)


def check(config):
    """The --ray options (an ExperimentError naming the flag)."""
    gpus, cpus = resources(config)
    if gpus < 0 or (config.device == "cpu" and gpus > 0):
        raise ExperimentError(f"--num-gpus {gpus:g}: 0 or more, and 0 with --device cpu")
    if config.device == "cuda" and gpus <= 0:
        raise ExperimentError(f"--num-gpus {gpus:g}: more than 0 with --device cuda")
    if gpus > 1 and gpus != int(gpus):
        raise ExperimentError(f"--num-gpus {gpus:g}: a fraction of one GPU, or whole GPUs")
    if cpus <= 0:
        raise ExperimentError(f"--cpus-per-unit {cpus:g}: more than 0")


def _package_path():
    """The folder holding this ``day2night`` package, first on the workers' PYTHONPATH."""
    return str(pathlib.Path(day2night.__file__).resolve().parents[1])


def start(ray, config):
    """Connect to Ray (a local instance with no address, else the cluster); returns whether
    this call started it (and so shuts it down). A driver that called ``ray.init`` itself
    keeps its own."""
    if ray.is_initialized():
        return False
    path = os.pathsep.join(p for p in (_package_path(), os.environ.get("PYTHONPATH")) if p)
    env = {"env_vars": {"PYTHONPATH": path}}
    kw = {"include_dashboard": False} if config.ray == "local" else {}
    ray.init(address=config.ray, runtime_env=env, log_to_driver=True, **kw)
    return True


def run(exp, work):
    """Every unit of ``work`` (Experiment.seeded_work) of the prepared Experiment ``exp`` on
    Ray: the pairs first, then the units, longest first."""
    ray = import_ray()
    started = start(ray, exp.config)
    try:
        gpus, cpus = resources(exp.config)
        log(f"Ray: {len(ray.nodes())} node(s), {ray.cluster_resources().get('CPU', 0):g} CPU, "
            f"{ray.cluster_resources().get('GPU', 0):g} GPU; each unit asks for {gpus:g} GPU "
            f"and {cpus:g} CPU")
        state = copy.copy(exp)
        state.runlog = None  # the driver's log; a task logs to its stderr (Ray forwards it)
        # the workers' current folder is not the driver's: every path absolute
        state.out, state.source = exp.out.resolve(), copy.copy(exp.source)
        state.source.out = state.out
        ref = ray.put(state)
        _make_pairs(ray, exp, ref, work)
        _run_units(ray, exp, ref, work, gpus, cpus)
    finally:
        if started:
            ray.shutdown()


def _make_pairs(ray, exp, ref, work):
    jobs = cost.pair_jobs(exp, work)
    if not jobs:
        return
    log(f"making {len(jobs)} cached pair group(s) on Ray")
    task = ray.remote(_pair_task).options(num_cpus=1, max_retries=MAX_RETRIES)
    refs = [task.remote(ref, job) for job in jobs]
    for r in refs:
        _get(ray, r)


def _pair_task(state, job):
    """One Ray task: the cached pairs of ``job`` (cost.pair_jobs)."""
    kind, *args = job
    getattr(state.source, kind)(*args)


def _get(ray, r):
    """``ray.get(r)``, a task's own exception raised as itself (its message, no trace)."""
    try:
        return ray.get(r)
    except ray.exceptions.RayTaskError as e:
        cause = getattr(e, "cause", None)
        raise (cause if isinstance(cause, Exception) else e) from None


def _run_units(ray, exp, ref, work, gpus, cpus):
    costs = cost.unit_costs(exp, work)
    order = sorted(range(len(work)), key=lambda i: -costs[i])  # stable: ties keep run order
    task = ray.remote(_unit_task).options(num_gpus=gpus, num_cpus=cpus,
                                          max_retries=MAX_RETRIES, retry_exceptions=False)
    pending = {}
    for i in order:
        pending[task.remote(ref, work[i], i + 1, len(work))] = i
    total, start_t, done_cost, failed = len(work), time.monotonic(), 0.0, []
    left = sum(costs)
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        i = pending.pop(ready[0])
        seed, t, row, fold, _ = work[i]
        uid = runfolder.unit_id(t, row.id, fold, seed)
        left -= costs[i]
        try:
            ran = _get(ray, ready[0])
        except Exception as e:  # the unit's own failure: the others go on
            failed.append((uid, _one_line(e)))
            log(f"unit {uid} failed: {_one_line(e)}")
            continue
        done_cost += costs[i]
        log(progress(total - len(pending), total, uid, ran, time.monotonic() - start_t,
                     done_cost, left))
    if failed:
        raise UnitsFailed(failure_message(exp.out, failed, total))


def _one_line(e):
    lines = [ln.strip() for ln in str(e).splitlines() if ln.strip()]
    return f"{type(e).__name__}: {lines[0] if lines else ''}".rstrip(": ")


def failure_message(out, failed, total):
    uid, why = failed[0]
    more = f" (and {len(failed) - 1} more: {', '.join(u for u, _ in failed[1:])})" \
        if len(failed) > 1 else ""
    return (f"unit {uid} failed: {why}{more}; the other {total - len(failed)} unit(s) are "
            f"done and kept in {out}: rerun the same command to run only the failed "
            f"unit(s) again (from their last checkpoint), or add --restart-unit {uid} to "
            "train it from scratch")


def progress(done, total, uid, ran, elapsed, done_cost, left_cost):
    """The line of a finished unit: units done of total, its node, its time, the run's ETA
    (the time so far per patch-step done, times the patch-steps left)."""
    if ran is None:
        return f"{done}/{total} units: {uid} was done already (scores.json)"
    eta = "-" if not done_cost else _duration(elapsed / done_cost * max(left_cost, 0))
    return (f"{done}/{total} units: {uid} done on node {ran['ip']} "
            f"({ran['node_id'][:8]}) in {_duration(ran['seconds'])}; ETA {eta}")


def _duration(s):
    s = int(round(s))
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{s % 3600 // 60:02d}m"


def _unit_task(state, item, index, total):
    """One Ray task: the serial run's ``run_unit`` of ``item`` (seed, task, row, fold, split);
    returns where and how long it ran (None when the unit was done), also written to the
    unit's folder as node.json."""
    ray = import_ray()
    seed, t, row, fold, _ = item
    udir = runfolder.unit_dir(state.out, runfolder.unit_id(t, row.id, fold, seed))
    if (udir / "scores.json").is_file():
        return None
    t0 = time.monotonic()
    state.run_unit(*item, index, total)
    ctx = ray.get_runtime_context()
    ran = {"node_id": ctx.get_node_id(), "ip": ray.util.get_node_ip_address(),
           "host": socket.gethostname(), "pid": os.getpid(),
           "seconds": round(time.monotonic() - t0, 3)}
    write_json(udir / NODE_RECORD, ran)
    return ran
