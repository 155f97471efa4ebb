"""``python -m day2night.experiment``: train and score every row of the paper's Tables 1 and 2.

The flags are ExperimentConfig's fields (config.py: each one's default, help and choices
written once there)."""

import argparse
import sys

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


def main(argv=None):
    cfg = parse(argv)
    try:
        if cfg.plan:
            plan.show(cfg)
        else:
            Experiment(cfg).run()
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
        # a killed DataLoader worker, torch out of memory...: the run stopped after its last
        # complete epoch (last.pt), so the same command resumes it
        what = "a DataLoader worker died" if "DataLoader worker" in str(e) else \
            f"training stopped ({type(e).__name__})"
        print(f"day2night.experiment: error: {what}: {one_line(e)[:300]}; {RESUME}",
              file=sys.stderr)
        return 1
    except ImportError as e:
        print(f"day2night.experiment: error: {e} (pip install torch: the train extra; from a "
              "checkout scripts/dev-install.sh installs it)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"day2night.experiment: interrupted: {RESUME}", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
