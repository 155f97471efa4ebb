"""``--plan``: the run's units, their patch-steps, the estimated GPU-hours and the resources
``--ray`` asks for, printed to stdout; nothing is written (the inputs are read and checked
as a run reads them, the folds made as a run would make them, without writing them)."""

import sys

from . import burst, cost, distributed, prepare, runfolder
from .runner import Experiment
from .source import PairSource


def show(config, file=None):
    """Print the plan of the run ``config`` would make (to ``file``, default stdout)."""
    file = file or sys.stdout
    exp = Experiment(config)
    c = exp.config
    exp.inputs = prepare.read_inputs(c.day, c.real, exp.tasks)
    exp.rows, exp.left_out = burst.burst_rows(c, exp.inputs, exp.rows)
    exp.plan = prepare.plan_folds(exp.out, c, exp.inputs, exp.rows)
    exp.source = PairSource(exp.out, c, exp.inputs, exp.target_isps, exp.tasks)
    work = exp.seeded_work()
    costs = cost.unit_costs(exp, work)
    gpus, cpus = distributed.resources(c)
    rows = []
    for (seed, task, row, fold, _), steps in zip(work, costs):
        uid = runfolder.unit_id(task, row.id, fold, seed)
        done = (runfolder.unit_dir(exp.out, uid) / "scores.json").is_file()
        rows.append((uid, steps, cost.gpu_hours(steps, c.patch), done))
    width = max(len(r[0]) for r in rows)
    print(f"{'unit':<{width}}  {'patch-steps':>14}  {'GPU-hours':>9}", file=file)
    for uid, steps, hours, done in sorted(rows, key=lambda r: -r[1]):
        print(f"{uid:<{width}}  {steps:>14,}  {hours:>9.2f}{'  (done)' if done else ''}",
              file=file)
    total = sum(r[1] for r in rows)
    left = sum(r[1] for r in rows if not r[3])
    hours = cost.gpu_hours(total, c.patch)
    print(f"{len(rows)} units ({sum(r[3] for r in rows)} done), {total:,} patch-steps: "
          f"about {hours:.2f} GPU-hours ({cost.gpu_hours(left, c.patch):.2f} left), at "
          f"{cost.GFLOP_PER_PATCH_STEP} GFLOP per 64 x 64 patch per training step (width 32, "
          f"scaled by the patch's area) and an assumed effective "
          f"{cost.ASSUMED_TFLOPS:g} TFLOP/s; validation and scoring not counted",
          file=file)
    where = "one process, serially (no --ray)" if c.ray is None else \
        f"Ray ({'a local instance' if c.ray == 'local' else c.ray})"
    print(f"runs on {where}; with --ray each unit asks for {gpus:g} GPU and {cpus:g} CPU "
          f"(--device {c.device})", file=file)
    return rows
