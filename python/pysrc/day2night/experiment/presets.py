"""The experiment's named training presets (docs/experiment.md), the values
``ExperimentConfig.with_preset`` (config.py) gives the options the command line left out:

- ``paper``: the paper's training (UNet width 32, 500 epochs, batches of 128 patches of
  64 x 64): a GPU job.
- ``mini``: proof that the night ISP learns on a 2-core CPU: a UNet of width 8 on patches of
  32 x 32 in batches of 8 (64 times the steps per epoch of 64 x 64 patches in batches of 128
  on the same images), Adam at lr 1e-2 (10 times the paper's: measured to reach in a few
  hundred steps what 1e-3 reaches in thousands), 40 epochs. On the stand-in captures of
  docs/experiment.md ("The mini preset") both tables train in under 30 minutes on 2 cores.

An option given on the command line wins over the preset's. Options that change the numbers
(patch, batch, amp, channels_last) are written to RUN/config.json only when they differ from
the paper's (``ExperimentConfig.record``), so a run folder of an earlier version resumes as
before."""

#: The source name of these values in a config field's ``default_from`` (config.py).
FROM_PRESET = "preset"
PAPER = {"epochs": 500, "width": 32, "patch": 64, "batch": 128, "lr": 1e-3}
#: The paper's cross-validation folds (``--folds``' default without a fold file; not a preset
#: value: a fold file's count wins).
PAPER_FOLDS = 3
PRESETS = {
    "paper": dict(PAPER),
    "mini": {"epochs": 40, "width": 8, "patch": 32, "batch": 8, "lr": 1e-2},
}
