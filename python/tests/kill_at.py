"""Test-only launcher for the resume tests: ``python kill_at.py N E S MODULE ARGS...`` runs
``python -m MODULE ARGS...`` with the N-th ``trainer.train`` call (1-based) given an
``on_step`` callback that SIGKILLs the process before step S of epoch E (0-based): a real
kill mid-training at a point fixed by the training itself, not by a clock. The library has
no test hook; this script installs the callback from outside."""

import os
import runpy
import signal
import sys

from day2night.train import trainer


def main():
    nth, epoch, step = map(int, sys.argv[1:4])
    module, train, calls = sys.argv[4], trainer.train, []

    def kill(e, s):
        if (e, s) == (epoch, step):
            os.kill(os.getpid(), signal.SIGKILL)

    def counted(*args, **kwargs):
        calls.append(None)
        if len(calls) == nth:
            kwargs["on_step"] = kill
        return train(*args, **kwargs)

    trainer.train = counted
    sys.argv = [module, *sys.argv[5:]]
    runpy.run_module(module, run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
