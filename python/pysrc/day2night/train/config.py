"""The trainer's settings, :class:`TrainConfig`: a module that works without torch, so that
``python -m day2night.train --help`` and the experiment's checks run where torch is not
installed (torch, from _torch.py, is asked only whether a CUDA device is there)."""

import dataclasses

from ._torch import torch


def _opt(default, help=None, **argparse):
    """A TrainConfig field; ``help`` and ``argparse`` (flags, choices, action) make its
    ``python -m day2night.train`` flag (train/__main__.py)."""
    return dataclasses.field(default=default, metadata={"help": help, **argparse})


@dataclasses.dataclass
class TrainConfig:
    """The trainer's settings (``python -m day2night.train --help`` lists them as flags,
    made from the fields: each default, help and choice is written once, here)."""

    out_dir: str = _opt(dataclasses.MISSING, "run folder (checkpoints, history)",
                        flags=("-o", "--out"), metavar="OUT", required=True)
    epochs: int = _opt(500, "training epochs (the paper: 500)")
    batch_size: int = _opt(128, "patches per step (global)")
    lr: float = _opt(1e-3, "Adam's learning rate (the paper: 1e-3)")
    decay_at: float = _opt(0.8, "fraction of the epochs after which the rate is x0.1 "
                           "(--decay)")
    decay: float = _opt(0.1, "the rate's factor from --decay-at on")
    init_features: int = _opt(32, "UNet width (32 in the paper)")
    seed: int = _opt(0, "seed of the initial weights and of the patch order")
    device: str = _opt("cpu", "cpu or cuda")
    workers: int = _opt(0, "DataLoader worker processes")
    progress: bool = _opt(True, "no progress line on stderr", flags=("--no-progress",),
                          action="store_false")
    #: Write the sample indices each rank trained on (out_dir/shards/), for checks.
    record_shards: bool = _opt(False, "write each rank's sample indices to OUT/shards/ "
                               "(checks)", action="store_true")
    #: Mixed precision: None (float32) or "bf16" (forward and backward under
    #: ``torch.autocast`` in bfloat16; weights, optimizer and loss stay float32).
    amp: str = _opt(None, "bfloat16 mixed precision (for GPUs)", choices=["bf16"])
    #: Channels-last (NHWC) memory format for the model and batches (faster on GPUs).
    channels_last: bool = _opt(False, "channels-last memory format (for GPUs)",
                               action="store_true")

    def check(self):
        if self.epochs < 1:
            raise ValueError(f"epochs {self.epochs} must be at least 1")
        if self.batch_size < 1:
            raise ValueError(f"batch_size {self.batch_size} must be at least 1")
        if not self.lr > 0:
            raise ValueError(f"lr {self.lr} must be positive")
        if not 0 <= self.decay_at <= 1:
            raise ValueError(f"decay_at {self.decay_at} must be in [0, 1]")
        if self.device not in ("cpu", "cuda") and not self.device.startswith("cuda:"):
            raise ValueError(f"device {self.device!r}: use cpu or cuda")
        if self.device.startswith("cuda"):
            if not torch.cuda.is_available():
                raise ValueError(f"device {self.device!r}: torch sees no CUDA device")
        if self.amp not in (None, "bf16"):
            raise ValueError(f"amp {self.amp!r}: use None (float32) or 'bf16'")

    def milestone(self):
        """The epoch (0-based) from which the rate is multiplied by ``decay``."""
        return int(round(self.decay_at * self.epochs))
