"""What each unit reads and what it costs, found without making anything: the cached pairs
Ray makes before the units (:func:`pair_jobs`), and each unit's patch-steps (its epochs
times the patches of its training inputs per epoch: :func:`unit_costs`), which order the
units longest first, give the run's ETA and ``--plan``'s estimate.

Both come from the serial run's own calls (``PairSource.train_val`` and ``tests``, as
``Experiment.run_unit`` makes them) on a :class:`_Recorder`, a PairSource that notes each
pair asked for instead of making it."""

import pathlib

import day2night

from ..isos import NOISY_ISOS
from ..variants import Isp
from . import names, pairs
from .source import PairSource
from .runfolder import RunFolderError, npy_header

#: GFLOP of one training step per 64 x 64 patch of the paper's UNet (width 32):
#: docs/experiment.md, "What it costs" (torch.utils.flop_counter, forward + backward).
GFLOP_PER_PATCH_STEP = 4.52
#: The effective throughput the GPU-hour estimate assumes (a data-centre GPU in float32
#: at about half its peak).
ASSUMED_TFLOPS = 10.0


class _Recorder(PairSource):
    """A PairSource that records the pairs asked for, returning ("real", scene) or
    ("day", name) markers instead of paths (nothing is made or read)."""

    def __init__(self, src):
        self.__dict__.update(src.__dict__)
        self.jobs = {}

    def real(self, sid, key):
        self.jobs.setdefault(("real", sid, key), ("real", sid, key))
        return ("real", sid)

    def synth(self, mode, name, key):
        # one synthesis makes every input key of a day image
        self.jobs.setdefault(("synth", mode, name), ("synth", mode, name, key))
        return ("day", name)


def _reads(rec, exp, item):
    """The training markers of the unit ``item`` (None: fresh synthesis; [] untrained or
    burst), after ``rec`` recorded every pair the unit reads."""
    seed, task, row, fold, split = item
    if row.source == "burst":
        for sid in exp.report_scenes:
            for iso in NOISY_ISOS:
                rec.real(sid, iso)
        return []
    test = split["test"] if split else sorted(exp.inputs.scenes)
    rec.tests(task, test)
    if row.source == "untrained":
        return []
    train, _ = rec.train_val(task, row, split, exp.plan.mixes)
    return train


def pair_jobs(exp, work):
    """The cached pair groups the units of ``work`` read, each once, in a fixed order:
    ("synth", mode, day image, key) (every key of the image is made) or ("real", scene,
    key), for ``getattr(PairSource, job[0])(*job[1:])``."""
    rec = _Recorder(exp.source)
    for item in work:
        if item[0] is None:  # the extra seeds read the same pairs
            _reads(rec, exp, item)
    return list(rec.jobs.values())


def unit_costs(exp, work):
    """Each unit's patch-steps (0 for the untrained and burst rows), in ``work``'s order."""
    rec, patches = _Recorder(exp.source), _Patches(exp)
    out = []
    for item in work:
        train = _reads(rec, exp, item)
        if train is None:  # fresh synthesis: the budget of Ours (data.fresh_budget)
            train = [("day", n) for n in exp.inputs.day_train]
        out.append(exp.config.epochs * sum(patches(m) for m in train))
    return out


def gpu_hours(patch_steps, patch):
    """Estimated GPU-hours of ``patch_steps`` steps of ``patch`` x ``patch`` patches (the
    FLOP count scales with the patch's area) at :data:`ASSUMED_TFLOPS`."""
    flop = patch_steps * GFLOP_PER_PATCH_STEP * 1e9 * (patch / 64) ** 2
    return flop / (ASSUMED_TFLOPS * 1e12) / 3600


class _Patches:
    """The ``--patch`` grid's patch count of a day image or real scene's network input: from
    its cached target's header when it exists, else from its DNG (the active area, or the
    release's window of it)."""

    def __init__(self, exp):
        self.exp, self.seen = exp, {}

    def __call__(self, marker):
        if marker not in self.seen:
            h, w = self._shape(marker)
            p = self.exp.config.patch
            self.seen[marker] = (h // p) * (w // p)
        return self.seen[marker]

    def _shape(self, marker):
        kind, name = marker
        out, inputs = pathlib.Path(self.exp.out), self.exp.inputs
        if kind == "real":
            cached = out / "data" / "real" / f"{names.scene_stem(name)}.y.npy"
            dng = inputs.scenes[name].clean_raw
        else:
            stem = names.day_stem(name)
            cached = [*sorted((out / "data").glob(f"synth-*/{stem}.y.npy")), None][0]
            dng = inputs.days[name]
        if cached is not None and cached.is_file():
            try:
                return npy_header(cached)[0][:2]
            except RunFolderError:
                pass
        return dng_shape(dng, self.exp.config.targets)


def dng_shape(path, targets):
    """(H, W) of the network input of a DNG: its active area, or the release's window."""
    raw = day2night.read_dng(str(path))
    h, w = raw.data.shape[:2]
    area = raw.meta.get("active_area")
    if area:
        h, w = int(area[2]) - int(area[0]), int(area[3]) - int(area[1])
    if targets == Isp.RELEASE:
        h, w = pairs.release_window(raw.meta, h, w)[2:]
    return int(h), int(w)
