"""``python -m day2night.experiment``: train and score every row of the paper's Tables 1 and 2."""

import argparse
import sys

from .rows import ROWS

EPILOG = """rows: """ + ", ".join(f"{r.id} ({r.label})" for r in ROWS) + """

Writes RUN/table.md, RUN/table.json and RUN/index.html. A killed run resumes at the row and
epoch it reached when rerun with the same options. --width below 32 is for tests and smoke
runs only (the output says so). See docs/experiment.md."""


def parse(argv):
    p = argparse.ArgumentParser(
        prog="python -m day2night.experiment",
        description="The paper's experiment: train the night ISP on each row's data and score "
        "it on real night pairs (Tables 1 and 2).",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--day", required=True, metavar="DAY_DIR",
                   help="day DNGs to synthesize from (sorted: the first 60 train, the rest validate)")
    p.add_argument("--real", required=True, metavar="REAL_DIR",
                   help="real night pairs written by `day2night real-pairs`")
    p.add_argument("-o", "--output", required=True, metavar="RUN", help="run folder")
    p.add_argument("--task", default="both", choices=["clean", "noisy", "both"])
    p.add_argument("--epochs", type=int, default=500, help="training epochs (paper: 500)")
    p.add_argument("--device", default="cpu", choices=["cpu", "cuda"])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--folds", type=int, default=3, help="cross-validation folds (paper: 3)")
    p.add_argument("--rows", nargs="+", metavar="ROW", help="rows to run (default: all)")
    p.add_argument("--width", type=int, default=32,
                   help="UNet init_features (paper: 32; smaller only for tests and smoke runs)")
    p.add_argument("--show", type=int, default=3, help="test scenes per row in index.html")
    return p.parse_args(argv)


def main(argv=None):
    args = parse(argv)
    from .folds import FoldError
    from .mix import MixError
    from .runner import Experiment, ExperimentError

    try:
        exp = Experiment(args.day, args.real, args.output, task=args.task, epochs=args.epochs,
                         device=args.device, seed=args.seed, folds=args.folds, rows_=args.rows,
                         width=args.width, show=args.show)
        exp.run()
    except (ExperimentError, FoldError, MixError, ValueError) as e:
        print(f"day2night.experiment: error: {e}", file=sys.stderr)
        return 2
    except ImportError as e:
        print(f"day2night.experiment: error: {e} (pip install day2night[train])", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("day2night.experiment: interrupted: rerun the same command to resume",
              file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
