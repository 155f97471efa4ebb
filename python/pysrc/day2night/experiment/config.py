"""The experiment's options as one record: :class:`ExperimentConfig` (docs/experiment.md).

Each option is a field written once, with its default, help text, choices and flag
spelling in the field's metadata; the command line of ``python -m day2night.experiment`` is
made from the fields (:func:`add_flags`), a named preset (presets.py) fills the training
options the command line left out (:meth:`ExperimentConfig.with_preset`), :func:`check`
validates the options, and :func:`resolve` settles what depends on the inputs (the
protocol, from the real set and the fold file, and the rows). :meth:`ExperimentConfig.record`
is ``RUN/config.json``: what a resume compares (:data:`CONFIG_KEYS`).

Metadata of a field: ``help``, ``flags`` (its spellings; none: not a flag), ``group`` (the
help's section), ``argparse`` (choices, metavar, nargs, action, required) and ``record``:
``"always"`` (in config.json), ``"paper"`` (in config.json only when not the paper's value,
``paper``, so a run folder of an earlier version resumes as before), ``"set"`` (in
config.json when given, not compared) or None (not recorded: it changes no number)."""

import dataclasses
import pathlib

from . import presets, protocol, rows
from .protocol import NOISE, PROTOCOLS, SYNTH_ISO, TARGETS

PROTOCOL = "protocol (each also set by --protocol release)"
TRAINING = "training"


class ExperimentError(ValueError):
    """Bad input of the experiment (the message names the file, scene or option)."""


def opt(default=None, help=None, flags=None, group=None, record=None, paper=None, **argparse):
    """A field of :class:`ExperimentConfig` with its command line in its metadata."""
    meta = {"help": help, "flags": flags, "group": group, "record": record, "paper": paper,
            "argparse": argparse}
    return dataclasses.field(default=default, metadata=meta)


def _paper(name, help, **kw):
    """A training option recorded only when it is not the paper's."""
    return opt(help=help, group=TRAINING, record="paper", paper=presets.PAPER[name], **kw)


@dataclasses.dataclass(frozen=True)
class ExperimentConfig:
    """Every option of ``python -m day2night.experiment`` (its ``--help``, field by field)."""

    day: str = opt(help="day DNGs to synthesize from (sorted: the first 60 train, the rest "
                   "validate)", record="always", metavar="DAY_DIR", required=True)
    real: str = opt(help="real night pairs written by `day2night real-pairs`",
                    record="always", metavar="REAL_DIR", required=True)
    output: str = opt(help="run folder", flags=("-o", "--output"), metavar="RUN", required=True)
    captures: str = opt(help="the capture folders REAL_DIR was made from (the SCENES of "
                        "`day2night real-pairs`): the burst row averages their ISO 1600 and "
                        "3200 bursts (without it the row is left out)", record="set",
                        metavar="SCENES")
    task: str = opt("both", record="always", choices=["clean", "noisy", "both"])
    epochs: int = opt(help="training epochs (paper and default: 500; --preset mini: 40)",
                      record="always")
    device: str = opt("cpu", record="always", choices=["cpu", "cuda"])
    seed: int = opt(0, record="always")
    folds: int = opt(help="cross-validation folds (default and paper: 3; with --folds-file: "
                     "the file's)", record="always")
    rows: tuple = opt(help="rows to run (default: all)", record="always", nargs="+",
                      metavar="ROW")
    width: int = opt(help="UNet init_features (paper and default: 32; smaller for tests, smoke "
                     "runs and --preset mini: 8)", record="always")
    show: int = opt(3, help="test scenes per row in index.html")
    restart_unit: tuple = opt((), help="delete this unit's folder and train it again "
                              "(repeatable), e.g. clean/ours/all or noisy/supervised/1; for a "
                              "damaged unit", action="append", metavar="TASK/ROW/FOLD")
    protocol: str = opt(help="preset: release sets the four options below to the release's",
                        group=PROTOCOL, record="always", choices=list(PROTOCOLS))
    targets: str = opt(help="ISP of every target (default: the one that made the real set's)",
                       group=PROTOCOL, record="always", choices=list(TARGETS))
    noise: str = opt(help="noise of synthetic noisy inputs: the synthesis' model, or the "
                     "release's S20 FE table clipped to [0, 1023] and truncated",
                     group=PROTOCOL, record="always", choices=list(NOISE))
    synth_iso: str = opt(help="ISO of a synthetic noisy slot: alternate by position, or drawn "
                         "at random per day image as the release does", group=PROTOCOL,
                         record="always", choices=list(SYNTH_ISO))
    folds_file: str = opt(help="the release's utils/k_fold_indices_saved.p or its JSON export: "
                          "its fold lists instead of seeded folds", group=PROTOCOL,
                          record="always", metavar="PATH")
    #: The fold file's SHA-256 (set by :func:`resolve`; no flag).
    folds_sha256: str = opt(record="always", flags=())
    preset: str = opt(help="named settings: paper (the default) or mini (learns on a 2-core "
                      "CPU in minutes: width 8, 32 x 32 patches, batch 8, lr 1e-2, 40 epochs)",
                      group=TRAINING, record="set", choices=sorted(presets.PRESETS))
    patch: int = _paper("patch", "training patch side (paper: 64; a multiple of 16)")
    batch: int = _paper("batch", "patches per training step (paper: 128)")
    lr: float = _paper("lr", "Adam's learning rate (paper: 1e-3)")
    workers: int = opt(0, help="DataLoader worker processes (the same batches with any "
                       "number)", group=TRAINING)
    amp: str = opt(help="bfloat16 mixed precision (for GPUs)", group=TRAINING, record="paper",
                   choices=["bf16"])
    channels_last: bool = opt(False, help="channels-last memory format (for GPUs)",
                              group=TRAINING, record="paper", paper=False,
                              action="store_true")

    def with_preset(self):
        """This config with the preset's values (``paper`` without one) where it has none."""
        values = presets.PRESETS[self.preset or "paper"]
        return dataclasses.replace(self, **{k: v for k, v in values.items()
                                            if getattr(self, k) is None})

    def check(self):
        """Validate the options (preset applied): an ExperimentError naming the flag."""
        check_options(self)

    @property
    def smoke(self):
        """A network narrower than the paper's: for tests and smoke runs."""
        return self.width < 32

    def record(self):
        """``RUN/config.json``: the recorded options (the module's docstring), as written
        before this class existed (an earlier run folder resumes)."""
        out = {}
        for f in dataclasses.fields(self):
            how, value = f.metadata["record"], getattr(self, f.name)
            if how == "always" or (how == "paper" and value != f.metadata["paper"]) \
                    or (how == "set" and value):
                out[f.name] = list(value or ()) if f.name == "rows" else value
        return out


#: The options a resume compares with the earlier run's config.json, in the order it names
#: the first that differs (every field recorded "always" or "paper"; a test checks).
CONFIG_KEYS = ("day", "real", "task", "epochs", "seed", "folds", "width", "device", "rows",
               "protocol", "targets", "noise", "synth_iso", "folds_file", "folds_sha256",
               "patch", "batch", "lr", "amp", "channels_last")
#: The value of a training option absent from config.json: the paper's.
PAPER_VALUES = {f.name: f.metadata["paper"] for f in dataclasses.fields(ExperimentConfig)
                if f.metadata["record"] == "paper"}


def flags_of(f):
    return f.metadata["flags"] if f.metadata["flags"] is not None else \
        ("--" + f.name.replace("_", "-"),)


def add_flags(p):
    """The fields' flags on the argparse parser ``p`` (sections: the fields' groups)."""
    groups = {None: p}
    for f in dataclasses.fields(ExperimentConfig):
        flags, kw = flags_of(f), dict(f.metadata["argparse"])
        if not flags:
            continue
        if f.metadata["group"] not in groups:
            groups[f.metadata["group"]] = p.add_argument_group(f.metadata["group"])
        if f.type in (int, float):
            kw["type"] = f.type
        if not kw.get("required"):
            kw["default"] = list(f.default) if kw.get("action") == "append" else f.default
        groups[f.metadata["group"]].add_argument(*flags, dest=f.name, help=f.metadata["help"],
                                                 **kw)
    return p


def from_args(args):
    """The ExperimentConfig of parsed arguments (``add_flags``'), its preset applied."""
    names = [f.name for f in dataclasses.fields(ExperimentConfig) if flags_of(f)]
    values = {n: getattr(args, n) for n in names}
    for n in ("rows", "restart_unit"):
        values[n] = None if values[n] is None else tuple(values[n])
    return ExperimentConfig(**values).with_preset()


def check_options(c):
    """The checks of :meth:`ExperimentConfig.check` (the messages name the flags)."""
    if c.patch < 16 or c.patch % 16:
        raise ExperimentError(f"--patch {c.patch}: a positive multiple of 16 (the UNet pools "
                              "4 times)")
    if c.batch < 1:
        raise ExperimentError(f"--batch {c.batch}: at least 1")
    if not 0 < float(c.lr) < 1:
        raise ExperimentError(f"--lr {float(c.lr)}: between 0 and 1")
    if c.workers < 0:
        raise ExperimentError(f"--workers {c.workers}: at least 0")
    if c.epochs < 1:
        raise ExperimentError(f"--epochs {c.epochs}: at least 1")
    if c.width < 1:
        raise ExperimentError(f"--width {c.width}: at least 1 (the paper's network: 32)")
    if c.device not in ("cpu", "cuda"):
        raise ExperimentError(f"--device {c.device!r}: use cpu or cuda")
    if not 0 <= c.seed <= 2**32 - 1:
        raise ExperimentError(f"--seed {c.seed}: use 0 to {2**32 - 1} (numpy's RandomState)")
    if c.show < 0:
        raise ExperimentError(f"--show {c.show}: at least 0 (test scenes on index.html)")
    protocol.check_flags(c.protocol, c.targets, c.noise, c.synth_iso, c.folds_file)
    rows.tasks_of(c.task)
    rows.select(list(c.rows or ()))


def typed(config):
    """``config`` with each number and switch of its field's type (``int(epochs)``, ...)."""
    return dataclasses.replace(config, **{
        f.name: f.type(getattr(config, f.name)) for f in dataclasses.fields(config)
        if f.type in (int, float, bool) and getattr(config, f.name) is not None})


def resolve(config):
    """The run's config: preset applied, checked, the day and real folders absolute, the
    protocol resolved (protocol.for_run: the real set's target ISP, the fold file) and the
    rows chosen (protocol.fresh_rows). Returns (config, {scene: ISP of its real target})."""
    c = typed(config.with_preset())
    c.check()
    c, isps = protocol.for_run(c)
    named = list(c.rows or ())
    chosen = protocol.fresh_rows(rows.select(named), c.targets, c.noise, bool(named))
    chosen = rows.for_tasks(chosen, c.task, bool(named))
    c = dataclasses.replace(
        c, day=str(pathlib.Path(c.day).resolve()), real=str(pathlib.Path(c.real).resolve()),
        captures=str(pathlib.Path(c.captures).resolve()) if c.captures else None,
        rows=tuple(r.id for r in chosen), restart_unit=tuple(dict.fromkeys(c.restart_unit)))
    return c, isps
