"""Training of the night ISP as the paper does it (Sec. 4.1; the release's train.py):
L1 loss, Adam at lr 1e-3, the rate multiplied by 0.1 at 80 % of the epochs, batches of 128
patches of 64 x 64, the checkpoint of the lowest validation loss kept.

Small pure pieces: ``make_model``, ``make_loader``, ``train_epoch``, ``evaluate``,
``save_checkpoint``/``load_checkpoint``, and ``train`` which strings them together.

- Seeded: the model's initial weights come from ``torch.manual_seed(seed)``; the order of
  the patches of epoch e from ``DistributedSampler(seed=seed)`` at epoch e (also with one
  process), so a run on CPU with the same seed gives the same weights and scores.
- Resumable: ``out_dir/last.pt`` is written (atomically) after every epoch with the
  model, optimizer, scheduler, history and best score; ``train`` continues from it, and a
  run killed at any point finishes with the weights of an uninterrupted run.
- Data parallel: under ``torchrun --nproc-per-node N`` (WORLD_SIZE > 1) each rank trains on
  its ``DistributedSampler`` shard inside ``DistributedDataParallel`` (gloo on CPU, nccl on
  CUDA), ``batch_size`` is the global batch (each rank takes batch_size / N), the
  validation sums are all-reduced, and only rank 0 writes checkpoints.
"""

import collections
import contextlib
import dataclasses
import json
import math
import os
import pickle  # its UnpicklingError only: torch.load(weights_only=True) raises it
import sys
import time

from ..atomic import open_atomic, write_text
from ._torch import no_grad, torch
from .config import TrainConfig  # noqa: F401  (trainer.TrainConfig, as before)
from .data import EpochSampler, FreshPatches, collate
from .unet import UNet



def dist_info():
    """(rank, world size, local rank) from torchrun's environment; (0, 1, 0) without it."""
    world = int(os.environ.get("WORLD_SIZE", "1"))
    return int(os.environ.get("RANK", "0")), world, int(os.environ.get("LOCAL_RANK", "0"))


def make_model(cfg):
    """The UNet, its weights drawn from ``torch.manual_seed(cfg.seed)``."""
    torch.manual_seed(cfg.seed)
    return UNet(in_channels=3, out_channels=3, init_features=cfg.init_features)


def make_loader(dataset, cfg, rank, world, shuffle):
    """A DataLoader over this rank's ``DistributedSampler`` shard; a batch holds
    ``batch_size / world`` patches (items of several patches count as that many). With
    worker processes, a dataset that decodes its images (``FreshPatches``) decodes them here
    first (``preload``, within its cache's bounds), so that the workers forked from this
    process share them instead of each decoding every image it meets; ``FreshPatches``'
    workers then persist from epoch to epoch, their indices (epoch, index) pairs."""
    if cfg.workers > 0 and hasattr(dataset, "preload"):
        dataset.preload()
    sampler = torch.utils.data.DistributedSampler(
        dataset, num_replicas=world, rank=rank, shuffle=shuffle, seed=cfg.seed, drop_last=False)
    per_rank = max(1, cfg.batch_size // world)
    items = max(1, per_rank // getattr(dataset, "patches_per_item", 1))
    # Fresh synthesis keeps its workers from epoch to epoch: their indices carry the epoch
    # (EpochSampler), which set_epoch in this process could not give their copies.
    persistent = cfg.workers > 0 and isinstance(dataset, FreshPatches)
    loader = torch.utils.data.DataLoader(
        dataset, batch_size=items, sampler=EpochSampler(sampler, dataset) if persistent
        else sampler, num_workers=cfg.workers, persistent_workers=persistent,
        collate_fn=collate, pin_memory=cfg.device.startswith("cuda"))
    return loader, sampler


def autocast(cfg, device):
    """The forward's precision context: bfloat16 autocast under ``amp="bf16"``."""
    if cfg is not None and cfg.amp == "bf16":
        return torch.autocast(device_type=torch.device(device).type, dtype=torch.bfloat16)
    return contextlib.nullcontext()


def to_device(x, device, cfg=None):
    """A batch on ``device``, channels-last when ``cfg.channels_last``."""
    fmt = torch.channels_last if cfg is not None and cfg.channels_last else torch.contiguous_format
    return x.to(device, non_blocking=True, memory_format=fmt)


def train_epoch(model, loader, optimizer, device, epoch, progress=None, cfg=None,
                on_step=None):
    """One pass of L1 training; returns the mean loss over this rank's patches.
    ``on_step(epoch, step)``, when given, is called before each step (the caller's hook)."""
    model.train()
    total, count = 0.0, 0
    for step, (x, y) in enumerate(loader):
        if on_step is not None:
            on_step(epoch, step)
        x, y = to_device(x, device, cfg), y.to(device, non_blocking=True)
        optimizer.zero_grad(set_to_none=True)
        with autocast(cfg, device):
            p = model(x)
        loss = torch.nn.functional.l1_loss(p.float(), y)
        loss.backward()
        optimizer.step()
        total += float(loss.detach()) * x.shape[0]
        count += x.shape[0]
        if progress:
            progress(step + 1, len(loader), total / count)
    return total / max(count, 1), count


@no_grad
def evaluate(model, loader, device, world, cfg=None):
    """(mean L1, PSNR in dB of the mean squared error) over the validation patches, summed
    over all ranks."""
    model.eval()
    sums = torch.zeros(3, dtype=torch.float64, device=device)
    for x, y in loader:
        x, y = to_device(x, device, cfg), y.to(device)
        with autocast(cfg, device):
            p = model(x)
        p = p.float()
        sums[0] += torch.nn.functional.l1_loss(p, y, reduction="sum").double()
        sums[1] += torch.nn.functional.mse_loss(p, y, reduction="sum").double()
        sums[2] += y.numel()
    if world > 1:
        torch.distributed.all_reduce(sums)
    n = max(float(sums[2]), 1.0)
    mse = float(sums[1]) / n
    return float(sums[0]) / n, (10 * math.log10(1 / mse) if mse > 0 else float("inf"))


def _state(model):
    m = model.module if hasattr(model, "module") else model
    return {k: v.detach().cpu() for k, v in m.state_dict().items()}


def save_checkpoint(path, **state):
    """torch.save to a temporary file, then rename: never a half-written checkpoint. The
    state holds tensors and plain values only (dicts, lists, tuples, numbers, strings,
    None), so :func:`load_checkpoint` reads it with ``weights_only=True``."""
    with open_atomic(path) as f:
        torch.save(state, f)


def scheduler_state(scheduler):
    """The scheduler's state_dict in plain values: MultiStepLR's ``milestones`` Counter as a
    dict (:func:`load_scheduler` turns it back)."""
    state = dict(scheduler.state_dict())
    if isinstance(state.get("milestones"), collections.Counter):
        state["milestones"] = {int(k): int(v) for k, v in state["milestones"].items()}
    return state


def load_scheduler(scheduler, state):
    """``scheduler.load_state_dict`` of :func:`scheduler_state`'s plain values."""
    state = dict(state)
    if isinstance(state.get("milestones"), dict):
        state["milestones"] = collections.Counter(state["milestones"])
    scheduler.load_state_dict(state)


class CheckpointError(ValueError):
    """A checkpoint that cannot be used (the message names the file and the reason)."""


#: What ``last.pt`` holds for resuming (``best.pt``: model, config, epoch, history).
RESUME_STATE = ("model", "optimizer", "scheduler", "config", "epoch", "history", "best_val")


def load_checkpoint(path, device="cpu", keys=("model", "config", "epoch")):
    """The dict of a checkpoint, read with ``weights_only=True`` (tensors and plain values:
    a checkpoint is never unpickled, so one from elsewhere cannot run code); a file torch
    cannot read whole (truncated, garbage), one holding other objects, or one without
    ``keys`` is a :class:`CheckpointError` naming it."""
    try:
        ck = torch.load(path, map_location=device, weights_only=True)
    except pickle.UnpicklingError as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else ""
        raise CheckpointError(
            f"{path}: a checkpoint holding objects other than tensors and plain values is "
            f"not loaded (loading it could run code; {first[:160]})") from None
    except Exception as e:  # torch raises RuntimeError, EOFError, UnpicklingError, OSError...
        first = str(e).strip().splitlines()[0] if str(e).strip() else ""
        raise CheckpointError(f"{path}: damaged checkpoint, torch cannot read it "
                              f"({type(e).__name__}: {first})") from None
    missing = [k for k in keys if not isinstance(ck, dict) or k not in ck]
    if missing:
        raise CheckpointError(f"{path}: damaged checkpoint, it holds no {', '.join(missing)}")
    return ck


def load_model(path, device="cpu"):
    """The UNet of a checkpoint (``best.pt``/``last.pt``), in eval mode on ``device``."""
    ck = load_checkpoint(path, "cpu")
    try:
        model = UNet(3, 3, ck["config"]["init_features"])
        model.load_state_dict(ck["model"])
    except (KeyError, TypeError, ValueError, RuntimeError) as e:
        raise CheckpointError(f"{path}: damaged checkpoint, its model does not load "
                              f"({type(e).__name__}: {str(e)[:200]})") from None
    return model.to(device).eval()


class _Bar:
    """A one-line progress report on stderr (rank 0): epoch, step, loss, validation PSNR."""

    def __init__(self, enabled, epochs):
        self.enabled, self.epochs, self.last = enabled, epochs, 0.0
        self.val = None

    def step(self, epoch, step, steps, loss):
        now = time.monotonic()
        if self.enabled and (now - self.last > 0.5 or step == steps):
            self.last = now
            val = "" if self.val is None else f"  val PSNR {self.val:.2f} dB"
            sys.stderr.write(f"\repoch {epoch + 1}/{self.epochs}  step {step}/{steps}  "
                             f"loss {loss:.5f}{val}   ")
            sys.stderr.flush()

    def end(self, epoch, loss, val_loss, val_psnr, secs):
        self.val = val_psnr
        if self.enabled:
            sys.stderr.write(f"\repoch {epoch + 1}/{self.epochs}  loss {loss:.5f}  "
                             f"val loss {val_loss:.5f}  val PSNR {val_psnr:.2f} dB  "
                             f"({secs:.1f} s)\n")
            sys.stderr.flush()


def _setup(cfg):
    rank, world, local = dist_info()
    device = torch.device(cfg.device)
    if world > 1 and not torch.distributed.is_initialized():
        if cfg.device.startswith("cuda"):
            device = torch.device("cuda", local)
            torch.cuda.set_device(device)
        torch.distributed.init_process_group("nccl" if device.type == "cuda" else "gloo")
    return rank, world, device


def train(cfg, train_set, val_set, on_step=None):
    """Train (or resume from ``cfg.out_dir/last.pt``) and return ``{"best", "last",
    "history", "initial"}``: the paths of the best-validation and last checkpoints, one dict
    per epoch (``epoch``, ``loss``, ``val_loss`` = validation L1, ``val_psnr``, ``lr``,
    ``seconds``; also ``history.json``) and the untrained weights' ``val_loss``/``val_psnr``."""
    cfg.check()
    rank, world, device = _setup(cfg)
    os.makedirs(cfg.out_dir, exist_ok=True)
    run = _Run(cfg, rank, world, device, on_step)
    run.start(val_set)
    loader, sampler = make_loader(train_set, cfg, rank, world, shuffle=True)
    run.val_loader, _ = make_loader(val_set, cfg, rank, world, shuffle=False)
    for epoch in range(run.first, cfg.epochs):
        sampler.set_epoch(epoch)
        for ds in (train_set, val_set):
            if hasattr(ds, "set_epoch"):
                ds.set_epoch(epoch)
        if cfg.record_shards:
            _record(cfg, rank, epoch, list(iter(sampler)))
        run.epoch(epoch, loader)
    if rank == 0:
        write_text(os.path.join(cfg.out_dir, "history.json"), json.dumps(run.history, indent=1))
    return {"best": run.best, "last": run.last, "history": run.history,
            "initial": run.initial}


class _Run:
    """The state of one training run: model, optimizer, schedule, history, checkpoints."""

    def __init__(self, cfg, rank, world, device, on_step=None):
        self.cfg, self.rank, self.world, self.device = cfg, rank, world, device
        self.on_step = on_step  # train's hook: on_step(epoch, step) before each step
        self.last = os.path.join(cfg.out_dir, "last.pt")
        self.best = os.path.join(cfg.out_dir, "best.pt")
        self.model = make_model(cfg).to(device)
        if cfg.channels_last:
            self.model = self.model.to(memory_format=torch.channels_last)
        self.optimizer = torch.optim.Adam(self.model.parameters(), lr=cfg.lr)
        self.scheduler = torch.optim.lr_scheduler.MultiStepLR(
            self.optimizer, [cfg.milestone()], cfg.decay)
        self.history, self.best_val, self.first, self.initial = [], float("inf"), 0, None
        self.bar = _Bar(cfg.progress and rank == 0, cfg.epochs)
        self.val_loader = None

    def start(self, val_set):
        """Resume from last.pt, or score the untrained weights (``initial``)."""
        if os.path.isfile(self.last):
            ck = load_checkpoint(self.last, self.device)
            _check_resume(self.last, ck, self.cfg)
            self.model.load_state_dict(ck["model"])
            self.optimizer.load_state_dict(ck["optimizer"])
            load_scheduler(self.scheduler, ck["scheduler"])
            self.history, self.best_val = ck["history"], ck["best_val"]
            self.first, self.initial = ck["epoch"] + 1, ck.get("initial")
            if self.history:
                self.bar.val = self.history[-1]["val_psnr"]
        else:
            loader, _ = make_loader(val_set, self.cfg, self.rank, self.world, shuffle=False)
            vl, vp = evaluate(self.model, loader, self.device, self.world, self.cfg)
            self.initial = {"val_loss": vl, "val_psnr": vp}
        if self.world > 1:
            dev = self.device
            self.model = torch.nn.parallel.DistributedDataParallel(
                self.model, device_ids=[dev.index] if dev.type == "cuda" else None)

    def epoch(self, epoch, loader):
        cfg, t0 = self.cfg, time.monotonic()
        lr = self.optimizer.param_groups[0]["lr"]
        loss, n = train_epoch(self.model, loader, self.optimizer, self.device, epoch,
                              lambda s, S, lo, e=epoch: self.bar.step(e, s, S, lo), cfg,
                              self.on_step)
        if self.world > 1:
            t = torch.tensor([loss * n, n], dtype=torch.float64, device=self.device)
            torch.distributed.all_reduce(t)
            loss = float(t[0] / max(float(t[1]), 1.0))
        self.scheduler.step()
        val_loss, val_psnr = evaluate(self.model, self.val_loader, self.device, self.world, cfg)
        row = {"epoch": epoch, "loss": loss, "val_loss": val_loss, "val_psnr": val_psnr,
               "lr": lr, "seconds": time.monotonic() - t0}
        self.history.append(row)
        improved = val_loss < self.best_val
        self.best_val = min(self.best_val, val_loss)
        if self.rank == 0:
            state = _state(self.model)
            meta = {"config": dataclasses.asdict(cfg), "epoch": epoch, "history": self.history,
                    "best_val": self.best_val, "initial": self.initial,
                    "writer_rank": self.rank, "world_size": self.world}
            if improved:
                save_checkpoint(self.best, model=state, **meta)
            save_checkpoint(self.last, model=state, optimizer=self.optimizer.state_dict(),
                            scheduler=scheduler_state(self.scheduler), **meta)
        self.bar.end(epoch, loss, val_loss, val_psnr, row["seconds"])
        if self.world > 1:
            torch.distributed.barrier()


#: Settings a run cannot change when it resumes.
RESUME_KEYS = ("epochs", "batch_size", "lr", "decay_at", "decay", "init_features", "seed",
               "amp", "channels_last")
#: What a checkpoint written before a setting existed ran with.
_RESUME_DEFAULTS = {"amp": None, "channels_last": False}


def _check_resume(path, ck, cfg):
    """A checkpoint resumed with other settings would not give the run it claims: refuse.
    One without the state a resume needs is a CheckpointError."""
    missing = [k for k in RESUME_STATE if k not in ck]
    if missing:
        raise CheckpointError(f"{path}: damaged checkpoint, it holds no {', '.join(missing)}")
    old = ck.get("config", {})
    diff = [f"{k} {old.get(k, _RESUME_DEFAULTS.get(k))!r} -> {getattr(cfg, k)!r}"
            for k in RESUME_KEYS if old.get(k, _RESUME_DEFAULTS.get(k)) != getattr(cfg, k)]
    if diff:
        raise ValueError(f"{path}: written by a run with other settings ({'; '.join(diff)}); "
                         "use another out_dir or the same settings")


def finish():
    """End the process group torchrun's ranks joined (nothing without one)."""
    if torch.distributed.is_available() and torch.distributed.is_initialized():
        torch.distributed.destroy_process_group()


def _record(cfg, rank, epoch, indices):
    d = os.path.join(cfg.out_dir, "shards")
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, f"rank{rank}_epoch{epoch}.json"), "w") as f:
        json.dump(indices, f)
