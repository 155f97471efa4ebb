"""``python -m day2night.experiment``: train and score every row of the paper's Tables 1 and 2."""

import argparse
import sys

from . import presets
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
    p.add_argument("--epochs", type=int, default=None,
                   help="training epochs (paper and default: 500; --preset mini: 60)")
    p.add_argument("--device", default="cpu", choices=["cpu", "cuda"])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--folds", type=int, default=None,
                   help="cross-validation folds (default and paper: 3; with --folds-file: "
                   "the file's)")
    p.add_argument("--rows", nargs="+", metavar="ROW", help="rows to run (default: all)")
    p.add_argument("--width", type=int, default=None,
                   help="UNet init_features (paper and default: 32; smaller for tests, smoke "
                   "runs and --preset mini: 8)")
    p.add_argument("--show", type=int, default=3, help="test scenes per row in index.html")
    p.add_argument("--restart-unit", action="append", default=[], metavar="TASK/ROW/FOLD",
                   help="delete this unit's folder and train it again (repeatable), e.g. "
                   "clean/ours/all or noisy/supervised/1; for a damaged unit")
    protocol_flags(p)
    presets.flags(p)
    args = p.parse_args(argv)
    args.train_opts = presets.resolve(args)
    return args


def protocol_flags(p):
    """The release's protocol on request (protocol.py, docs/experiment.md)."""
    g = p.add_argument_group("protocol (each also set by --protocol release)")
    g.add_argument("--protocol", choices=["day2night", "release"],
                   help="preset: release sets the four options below to the release's")
    g.add_argument("--targets", choices=["release", "day2night"],
                   help="ISP of every target (default: the one that made the real set's)")
    g.add_argument("--noise", choices=["day2night", "release"],
                   help="noise of synthetic noisy inputs: the synthesis' model, or the "
                   "release's S20 FE table clipped to [0, 1023] and truncated")
    g.add_argument("--synth-iso", choices=["alternate", "release"],
                   help="ISO of a synthetic noisy slot: alternate by position, or drawn at "
                   "random per day image as the release does")
    g.add_argument("--folds-file", metavar="PATH",
                   help="the release's utils/k_fold_indices_saved.p or its JSON export: "
                   "its fold lists instead of seeded folds")


def main(argv=None):
    args = parse(argv)
    from .folds import FoldError
    from .mix import MixError
    from .runner import Experiment, ExperimentError

    try:
        exp = Experiment(args.day, args.real, args.output, task=args.task, epochs=args.epochs,
                         device=args.device, seed=args.seed, folds=args.folds, rows_=args.rows,
                         width=args.width, show=args.show, restart=args.restart_unit,
                         protocol=args.protocol, targets=args.targets, noise=args.noise,
                         synth_iso=args.synth_iso, folds_file=args.folds_file,
                         train_opts=args.train_opts)
        exp.run()
    except (ExperimentError, FoldError, MixError, ValueError) as e:
        print(f"day2night.experiment: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
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
