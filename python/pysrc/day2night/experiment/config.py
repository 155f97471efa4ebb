"""The experiment's options as one record: :class:`ExperimentConfig` (docs/experiment.md).

Each option is a field written once, with its default, help text, choices and flag
spelling in the field's metadata; the command line of ``python -m day2night.experiment`` is
made from the fields (:func:`add_flags`), a named preset (presets.py) fills the training
options the command line left out (:meth:`ExperimentConfig.with_preset`), :func:`check`
validates the options, and :func:`resolve` settles what depends on the inputs (the
protocol, from the real set and the fold file, and the rows). :meth:`ExperimentConfig.record`
is ``RUN/config.json``: what a resume compares (:data:`CONFIG_KEYS`).

Metadata of a field: ``help``, ``flags`` (its spellings; none: not a flag), ``group`` (the
help's section), ``argparse`` (choices, metavar, nargs, action, required), ``record``:
``"always"`` (in config.json), ``"paper"`` (in config.json only when not the paper's value,
``paper``, so a run folder of an earlier version resumes as before), ``"set"`` (in
config.json when given, not compared) or None (not recorded: it changes no number), and
``default_from``: where the option gets its value when the command line leaves it out, the
sources tried in order (:meth:`ExperimentConfig.with_defaults`): ``"preset"`` (the
``--preset``'s values, presets.py), ``"protocol"`` (the ``--protocol``'s, protocol.PRESETS),
``"real set"`` (the ISP of the real set's targets), ``"fold file"`` (its number of folds)
or the value itself. The only place a default is written."""

import dataclasses
import pathlib

from . import presets, protocol, rows
from .presets import FROM_PRESET
from .protocol import FROM_FOLD_FILE, FROM_PROTOCOL, FROM_REAL_SET
from .protocol import NOISE, PROTOCOLS, SYNTH_ISO, TARGETS

PROTOCOL = "protocol (each also set by --protocol release)"
TRAINING = "training"
SCALE = "at scale (Ray)"


class ExperimentError(ValueError):
    """Bad input of the experiment (the message names the file, scene or option)."""


#: The most training seeds of ``--seeds`` (each one trains every unit again).
MAX_SEEDS = 1000
#: The sources a field's ``default_from`` may name (anything else is a value).
SOURCES = (FROM_PRESET, FROM_PROTOCOL, FROM_REAL_SET, FROM_FOLD_FILE)


def opt(default=None, help=None, flags=None, group=None, record=None, paper=None,
        default_from=(), **argparse):
    """A field of :class:`ExperimentConfig` with its command line in its metadata."""
    meta = {"help": help, "flags": flags, "group": group, "record": record, "paper": paper,
            "default_from": tuple(default_from), "argparse": argparse}
    return dataclasses.field(default=default, metadata=meta)


def _paper(name, help, **kw):
    """A training option recorded only when it is not the paper's, from the preset (``{}``
    in ``help``: the paper's value)."""
    return opt(help=help.format(_num(presets.PAPER[name])), group=TRAINING, record="paper",
               paper=presets.PAPER[name], default_from=(FROM_PRESET,), **kw)


def _num(v):
    """A preset value as the help spells it: 500, 1e-3."""
    if isinstance(v, float) and v < 0.1:
        mantissa, exp = f"{v:e}".split("e")
        return f"{float(mantissa):g}e{int(exp)}"
    return f"{v:g}"


PAPER, MINI = presets.PAPER, presets.PRESETS["mini"]


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
    # (the recorded fields in the order a resume names the first that differs: CONFIG_KEYS)
    task: str = opt("both", record="always", choices=["clean", "noisy", "both"])
    epochs: int = opt(help=f"training epochs (paper and default: {PAPER['epochs']}; --preset "
                      f"mini: {MINI['epochs']})",
                      record="always", default_from=(FROM_PRESET,))
    seed: int = opt(0, help="seed of the folds, the synthetic data and the first training "
                    "seed", record="always")
    seeds: int = opt(1, help="train every unit with N seeds: --seed, --seed+1, ..., "
                     "--seed+N-1 (1 to 1000; the folds and synthetic data stay those of "
                     "--seed; the spread measures training variance, shown in the intervals)",
                     group=TRAINING, record="paper", paper=1, metavar="N")
    compare_to: str = opt(help="reference row of the table's paired comparisons (default: "
                          "day, the row the paper's claims are made against; untrained when "
                          "day is not run)", metavar="ROW")
    folds: int = opt(help=f"cross-validation folds (default and paper: {presets.PAPER_FOLDS}; "
                     "with --folds-file: the file's)", record="always",
                     default_from=(FROM_FOLD_FILE, presets.PAPER_FOLDS))
    width: int = opt(help=f"UNet init_features (paper and default: {PAPER['width']}; smaller "
                     f"for tests, smoke runs and --preset mini: {MINI['width']})",
                     record="always",
                     default_from=(FROM_PRESET,))
    device: str = opt("cpu", record="always", choices=["cpu", "cuda"])
    rows: tuple = opt(help="rows to run (default: all)", record="always", nargs="+",
                      metavar="ROW")
    show: int = opt(3, help="test scenes per row in index.html")
    restart_unit: tuple = opt((), help="delete this unit's folder and train it again "
                              "(repeatable), e.g. clean/ours/all or noisy/supervised/1, "
                              "seed-S/TASK/ROW/FOLD for an extra seed of --seeds; for a damaged "
                              "unit", action="append", metavar="TASK/ROW/FOLD")
    protocol: str = opt("day2night", help="preset: release sets the four options below to "
                        "the release's", group=PROTOCOL, record="always",
                        choices=list(PROTOCOLS))
    targets: str = opt(help="ISP of every target (default: the one that made the real set's)",
                       group=PROTOCOL, record="always", choices=list(TARGETS),
                       default_from=(FROM_PROTOCOL, FROM_REAL_SET))
    noise: str = opt(help="noise of synthetic noisy inputs: the synthesis' model, or the "
                     "release's S20 FE table clipped to [0, 1023] and truncated",
                     group=PROTOCOL, record="always", choices=list(NOISE),
                     default_from=(FROM_PROTOCOL,))
    synth_iso: str = opt(help="ISO of a synthetic noisy slot: alternate by position, or drawn "
                         "at random per day image as the release does", group=PROTOCOL,
                         record="always", choices=list(SYNTH_ISO),
                         default_from=(FROM_PROTOCOL,))
    folds_file: str = opt(help="the release's utils/k_fold_indices_saved.p or its JSON export: "
                          "its fold lists instead of seeded folds", group=PROTOCOL,
                          record="always", metavar="PATH")
    #: The fold file's SHA-256 (set by :func:`resolve`; no flag).
    folds_sha256: str = opt(record="always", flags=())
    preset: str = opt(help="named settings: paper (the default) or mini (learns on a 2-core "
                      f"CPU in minutes: width {MINI['width']}, {MINI['patch']} x "
                      f"{MINI['patch']} patches, batch {MINI['batch']}, lr {_num(MINI['lr'])}, "
                      f"{MINI['epochs']} epochs)",
                      group=TRAINING, record="set", choices=sorted(presets.PRESETS))
    patch: int = _paper("patch", "training patch side (paper: {}; a multiple of 16)")
    batch: int = _paper("batch", "patches per training step (paper: {})")
    lr: float = _paper("lr", "Adam's learning rate (paper: {})")
    workers: int = opt(0, help="DataLoader worker processes (the same batches with any "
                       "number)", group=TRAINING)
    amp: str = opt(help="bfloat16 mixed precision (for GPUs)", group=TRAINING, record="paper",
                   choices=["bf16"])
    channels_last: bool = opt(False, help="channels-last memory format (for GPUs)",
                              group=TRAINING, record="paper", paper=False,
                              action="store_true")

    # (where the units run: record None, they change no number; distributed.py, plan.py)
    ray: str = opt(help="run the units as Ray tasks: on a local Ray instance using every "
                   "GPU (or CPU with --device cpu) of this machine, or on the cluster at "
                   "ADDRESS (docs/experiment.md, \"At the paper's scale\")", group=SCALE,
                   nargs="?", const="local", metavar="ADDRESS")
    num_gpus: float = opt(help="GPUs per unit with --ray (default: 1 with --device cuda, "
                          "0 with cpu; a fraction lets units share a GPU)", group=SCALE,
                          metavar="N")
    cpus_per_unit: float = opt(help="CPUs per unit with --ray, for its loader (default: "
                               "--workers, at least 1)", group=SCALE, metavar="N")
    plan: bool = opt(False, help="print the units, their patch-steps, the estimated "
                     "GPU-hours and the resources asked for; write nothing", group=SCALE,
                     action="store_true")

    def with_preset(self):
        """This config with the preset's values (``paper`` without one) where it has none."""
        return self.with_defaults({FROM_PRESET: presets.PRESETS[self.preset or "paper"]})

    def with_defaults(self, sources):
        """This config with each option left out given by its field's ``default_from``
        (:func:`fill_defaults`)."""
        return fill_defaults(self, sources)

    def check(self):
        """Validate the options (preset applied): an ExperimentError naming the flag."""
        check_options(self)

    @property
    def seed_list(self):
        """The training seeds of every unit: ``seed``, ``seed + 1``, ... (``seeds`` of them)."""
        return [self.seed + i for i in range(self.seeds)]

    @property
    def label(self):
        """The settings named (table.json's "label"): "paper" or "mini" (the preset's
        training values), "smoke" (narrower than mini and fewer epochs), else "custom"."""
        values = {k: getattr(self, k) for k in presets.PAPER}
        for name in ("paper", "mini"):
            if values == presets.PRESETS[name]:
                return name
        mini = presets.PRESETS["mini"]
        if self.width < mini["width"] and self.epochs < mini["epochs"]:
            return "smoke"
        return "custom"

    @property
    def smoke(self):
        """A network narrower than the paper's: for tests and smoke runs."""
        return self.width < PAPER["width"]

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


def fill_defaults(config, sources):
    """``config`` with each option left out (None) given by its field's ``default_from``: the
    first source there that has a value for it. ``sources`` maps a source to {option:
    value}; a source it does not map is not known yet and leaves the option out (to be
    filled once it is known); an entry that is no source is the value itself."""
    values = {}
    for f in dataclasses.fields(config):
        if getattr(config, f.name) is not None:
            continue
        for src in f.metadata["default_from"]:
            if src not in SOURCES:
                values[f.name] = src
            elif src not in sources:
                break
            elif f.name in sources[src]:
                values[f.name] = sources[src][f.name]
            else:
                continue
            break
    return dataclasses.replace(config, **values)


#: The options a resume compares with the earlier run's config.json, in the order it names
#: the first that differs: every field recorded "always" or "paper", in field order.
CONFIG_KEYS = tuple(f.name for f in dataclasses.fields(ExperimentConfig)
                    if f.metadata["record"] in ("always", "paper"))
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
    if not 1 <= c.seeds <= min(MAX_SEEDS, 2**32 - c.seed):
        raise ExperimentError(f"--seeds {c.seeds}: 1 to {MAX_SEEDS}, and --seed + --seeds - 1 "
                              f"at most {2**32 - 1}")
    if c.compare_to is not None and c.compare_to != rows.UNTRAINED.id:
        try:
            rows.select([c.compare_to])
        except ValueError as e:
            raise ExperimentError(f"--compare-to: {e}") from None
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
    options left out given by their protocol, real set and fold file (protocol.for_run,
    :meth:`ExperimentConfig.with_defaults`) and the rows chosen (protocol.fresh_rows).
    Returns (config, {scene: ISP of its real target})."""
    c = typed(config.with_preset())
    c.check()
    c, isps, sources = protocol.for_run(c)
    c = c.with_defaults(sources)
    named = list(c.rows or ())
    chosen = protocol.fresh_rows(rows.select(named), c.targets, c.noise, bool(named))
    chosen = rows.for_tasks(chosen, c.task, bool(named))
    if not named and not c.captures:
        # the burst row needs --captures: without it the rows (config.json) are those of a
        # run folder made before the row existed, which resumes unchanged
        chosen = [r for r in chosen if r.source != "burst"]
    ids = [r.id for r in chosen]
    ref = c.compare_to or ("day" if "day" in ids else rows.UNTRAINED.id)
    if ref not in ids + [rows.UNTRAINED.id]:
        raise ExperimentError(f"--compare-to {ref}: not a row of this run (rows: "
                              f"{', '.join([rows.UNTRAINED.id] + ids)})")
    c = dataclasses.replace(
        c, compare_to=ref, day=str(pathlib.Path(c.day).resolve()),
        real=str(pathlib.Path(c.real).resolve()),
        captures=str(pathlib.Path(c.captures).resolve()) if c.captures else None,
        rows=tuple(r.id for r in chosen), restart_unit=tuple(dict.fromkeys(c.restart_unit)))
    return c, isps
