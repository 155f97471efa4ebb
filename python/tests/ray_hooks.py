"""Test-only launcher for the experiment's Ray fault tests: ``python ray_hooks.py ARGS...``
starts a local Ray instance whose worker processes run :func:`install` at start (Ray's
``worker_process_setup_hook``), then runs ``python -m day2night.experiment ARGS...`` on it
(the experiment keeps a Ray instance its driver started). The library has no test hook:
this installs one from outside, in the workers, through the environment:

- ``D2N_TEST_KILL_EPOCH=E`` and ``D2N_TEST_MARKER=PATH``: the first unit to reach step 0 of
  epoch E (0-based) creates PATH and kills its worker process (``os._exit``) there, once
  for the whole run (PATH made exclusively): Ray retries the unit, which resumes from its
  last checkpoint;
- ``D2N_TEST_FAIL_UNIT=TASK/ROW/FOLD``: that unit (of the first seed) raises an error of
  its own when it starts training, on every attempt (a bad unit: not retried)."""

import os
import pathlib
import runpy
import sys


def install():
    """Wrap the experiment's ``train`` (day2night.experiment.unit.train) in this worker."""
    from day2night.experiment import unit

    train = unit.train
    kill_epoch = os.environ.get("D2N_TEST_KILL_EPOCH")
    marker = os.environ.get("D2N_TEST_MARKER")
    fail = os.environ.get("D2N_TEST_FAIL_UNIT")

    def kill(epoch, step):
        if (epoch, step) == (int(kill_epoch), 0):
            try:
                fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                return
            os.write(fd, f"{os.getpid()}\n".encode())
            os.close(fd)
            os._exit(9)  # the worker process dies mid-unit, as a killed one does

    def wrapped(cfg, train_set, val_set, on_step=None):
        where = pathlib.Path(cfg.out_dir).as_posix()
        if fail and where.endswith(f"/units/{fail}/model") and "/seeds/" not in where:
            raise ValueError(f"injected failure of unit {fail}")
        return train(cfg, train_set, val_set, on_step=kill if kill_epoch else on_step)

    unit.train = wrapped


def main():
    import ray

    here = str(pathlib.Path(__file__).resolve().parent)
    path = os.pathsep.join(p for p in (here, os.environ.get("PYTHONPATH")) if p)
    os.environ["PYTHONPATH"] = path
    ray.init(address="local", include_dashboard=False,
             runtime_env={"worker_process_setup_hook": "ray_hooks.install",
                          "env_vars": {"PYTHONPATH": path, **{
                              k: v for k, v in os.environ.items()
                              if k.startswith("D2N_TEST_") or k == "OMP_NUM_THREADS"}}})
    sys.argv = ["day2night.experiment", *sys.argv[1:]]
    try:
        runpy.run_module("day2night.experiment", run_name="__main__", alter_sys=True)
    finally:
        ray.shutdown()


if __name__ == "__main__":
    main()
