"""The network input / target pairs of a run's units: :class:`PairSource` makes (or finds in
RUN/data, pairs.cached) the pair of a real scene or of a synthesized day image."""

import pathlib

from ..isos import NOISY_ISOS
from . import mix as mix_mod
from . import names, pairs, protocol
from .config import ExperimentError
from .rows import test_keys


class PairSource:
    """The pairs of one run: ``out`` the run folder, ``config`` its resolved
    ExperimentConfig (seed, targets, noise, synth_iso, task), ``inputs`` prepare.Inputs,
    ``target_isps`` {scene: ISP of its real target} (protocol.real_target_isps), ``tasks``
    the run's tasks."""

    def __init__(self, out, config, inputs, target_isps, tasks):
        self.out = pathlib.Path(out)
        self.config = config
        self.inputs = inputs
        self.target_isps = target_isps
        self.tasks = list(tasks)
        self.isos = protocol.run_isos(config.synth_iso, inputs.days, config.seed)

    def real(self, sid, key):
        """(x_path, y_path) of real scene ``sid`` for input key "clean" or an ISO."""
        scene = self.inputs.scenes[sid]
        stem = names.scene_stem(sid)  # within the file system's name limit
        name = f"{stem}_{key}" if key != "clean" else stem
        folder = self.out / "data" / "real"
        iso = None if key == "clean" else int(key)
        return pairs.cached(folder, {key: name}, lambda: {key: self._real_pair(scene, iso)})[key]

    def _real_pair(self, scene, iso):
        try:
            return pairs.real_pair(scene, iso, targets=self.config.targets,
                                   source=self.target_isps.get(scene.id, "day2night"))
        except (pairs.PairError, ValueError) as e:
            raise ExperimentError(str(e)) from None

    def synth(self, mode, name, key):
        """(x_path, y_path) of day image ``name`` synthesized in ``mode`` for input ``key``."""
        folder = self.out / "data" / f"synth-{mode}"
        stem = names.day_stem(name)  # within the file system's name limit
        files = {}
        if "clean" in self.tasks:
            files["clean"] = stem
        if "noisy" in self.tasks:
            files.update({iso: f"{stem}_{iso}" for iso in NOISY_ISOS})
        c = self.config

        def make():
            try:
                return pairs.synth_pairs(self.inputs.days[name], mode, c.seed,
                                         targets=c.targets, noise=c.noise)
            except (pairs.PairError, ValueError) as e:
                raise ExperimentError(str(e)) from None

        return pairs.cached(folder, files, make)[key]

    def slot_pair(self, slot, task, mode):
        """The pair of a training or validation slot (mix.py's dicts)."""
        key = "clean" if task == "clean" else slot["iso"]
        if slot["kind"] == "real":
            return self.real(slot["id"], key)
        return self.synth(mode, slot["id"], key)

    def train_val(self, task, row, split, mixes):
        """(training pairs, validation pairs) of a unit: a row with real data trains on its
        fold's mix (``mixes``: prepare.Plan's) and validates on the fold's real validation
        scenes; the others train and validate on the synthetic day images. The fresh row's
        training pairs are None (it synthesizes during training)."""
        if row.per_fold:
            train = mixes[row.id][split["fold"]]
            val = mix_mod.real_slots(split["val"])
        else:
            train, val = (protocol.synthetic_slots(d, self.isos)
                          for d in (self.inputs.day_train, self.inputs.day_val))
        val_p = [self.slot_pair(s, task, row.mode) for s in val]
        if row.source == "fresh":
            return None, val_p
        return [self.slot_pair(s, task, row.mode) for s in train], val_p

    def tests(self, task, test_scenes):
        """(scene, input key, (x_path, y_path)) of every test input of a unit."""
        return [(sid, k, self.real(sid, k)) for sid in test_scenes for k in test_keys(task)]
