"""``python -m day2night.experiment``: train and score every row of the paper's Tables 1 and 2.

The flags are ExperimentConfig's fields (config.py: each one's default, help and choices
written once there)."""

import argparse
import signal
import sys
import threading

from . import config, plan
from .rows import ROWS
from .folds import FoldError
from .mix import MixError
from .runner import Experiment, ExperimentError
from .distributed import UnitsFailed

EPILOG = """rows: """ + ", ".join(f"{r.id} ({r.label})" for r in ROWS) + """

Writes RUN/table.md, RUN/table.json and RUN/index.html. A killed run resumes at the row and
epoch it reached when rerun with the same options. --width below 32 is for tests and smoke
runs only (the output says so). See docs/experiment.md."""


def parser():
    p = argparse.ArgumentParser(
        prog="python -m day2night.experiment",
        description="The paper's experiment: train the night ISP on each row's data and score "
        "it on real night pairs (Tables 1 and 2).",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    return config.add_flags(p)


def parse(argv):
    """The ExperimentConfig of a command line (its preset applied; not yet checked)."""
    return config.from_args(parser().parse_args(argv))


RESUME = "rerun the same command to resume"


def one_line(e):
    """An error's message on one line: an error raised in a DataLoader worker (torch's
    "Caught X in DataLoader worker process N" and the worker's traceback) as the worker's
    own last line, else the message's first line."""
    lines = [ln.strip() for ln in str(e).strip().splitlines() if ln.strip()]
    if not lines:
        return type(e).__name__
    if len(lines) > 1 and any(ln.startswith("Original Traceback") for ln in lines):
        return lines[-1]
    return lines[0]


#: The messages of interruptions that the same command resumes: a DataLoader worker killed
#: from outside (the OOM killer, a signal), memory exhausted (torch's CPU and CUDA
#: allocators). Any other RuntimeError is a bug or bad data, which a rerun repeats.
WORKER_KILLED = ("is killed by signal", "exited unexpectedly")
OUT_OF_MEMORY = ("out of memory", "can't allocate memory")


class Terminated(BaseException):
    """SIGTERM (a scheduler's stop, ``kill``), raised in the main thread like Ctrl-C."""


def _on_sigterm(signum, frame):
    raise Terminated()


def stopped(e, unit=None):
    """(exit status, one-line message) of a RuntimeError or MemoryError that stopped the run
    (``unit``: the unit it was in, when known): "resume" only where resuming helps."""
    msg, where = one_line(e)[:300], f" in {unit}" if unit else ""
    if isinstance(e, MemoryError) or any(s in str(e) for s in OUT_OF_MEMORY):
        return 1, (f"out of memory{where}: {msg}; free memory (or lower --batch / --workers) "
                   f"and {RESUME} from its last complete epoch")
    if "DataLoader worker" in str(e) and any(s in str(e) for s in WORKER_KILLED):
        return 1, f"a DataLoader worker died{where}: {msg}; {RESUME}"
    return 1, (f"{type(e).__name__}{where}: {msg} (not an interruption: the same command "
               "stops here again; RUN/log.txt holds the run's output)")


def main(argv=None):
    cfg = parse(argv)
    exp = None
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _on_sigterm) if main_thread else None
    try:
        if cfg.plan:
            plan.show(cfg)
        else:
            exp = Experiment(cfg)
            exp.run()
    except UnitsFailed as e:
        print(f"day2night.experiment: error: {e}", file=sys.stderr)
        return 1
    except (ExperimentError, FoldError, MixError, ValueError) as e:
        print(f"day2night.experiment: error: {one_line(e)}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"day2night.experiment: error: {one_line(e)}", file=sys.stderr)
        return 2
    except (RuntimeError, MemoryError) as e:
        code, msg = stopped(e, getattr(exp, "current_unit", None))
        print(f"day2night.experiment: error: {msg}", file=sys.stderr)
        return code
    except ImportError as e:
        print(f"day2night.experiment: error: {e} (pip install torch: the train extra; from a "
              "checkout scripts/dev-install.sh installs it)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"day2night.experiment: interrupted: {RESUME}", file=sys.stderr)
        return 130
    except Terminated:
        print(f"day2night.experiment: terminated (SIGTERM): {RESUME}", file=sys.stderr)
        return 128 + signal.SIGTERM
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, previous)
    return 0


if __name__ == "__main__":
    sys.exit(main())
