"""Training options of the experiment and its named presets (docs/experiment.md).

- ``paper``: the paper's training (UNet width 32, 500 epochs, batches of 128 patches of
  64 x 64): a GPU job.
- ``mini``: proof that the night ISP learns on a 2-core CPU: a UNet of width 8 on patches of
  32 x 32 in batches of 8 (64 times the steps per epoch of 64 x 64 patches in batches of 128
  on the same images), Adam at lr 1e-2 (10 times the paper's: measured to reach in a few
  hundred steps what 1e-3 reaches in thousands), 40 epochs. On the stand-in captures of
  docs/experiment.md ("The mini preset") both tables train in under 30 minutes on 2 cores.

An option given on the command line wins over the preset's. Options that change the numbers
(patch, batch, amp, channels_last) are written to RUN/config.json only when they differ from
the paper's, so a run folder of an earlier version resumes as before."""

PAPER = {"epochs": 500, "width": 32, "patch": 64, "batch": 128, "lr": 1e-3}
PRESETS = {
    "paper": dict(PAPER),
    "mini": {"epochs": 40, "width": 8, "patch": 32, "batch": 8, "lr": 1e-2},
}
#: Written to config.json (and compared on a rerun) when not the paper's value.
TRAIN_KEYS = ("patch", "batch", "lr", "amp", "channels_last")
DEFAULTS = {"patch": 64, "batch": 128, "lr": 1e-3, "amp": None, "channels_last": False}


def flags(p):
    """The training options of ``python -m day2night.experiment``."""
    g = p.add_argument_group("training")
    g.add_argument("--preset", choices=sorted(PRESETS),
                   help="named settings: paper (the default) or mini (learns on a 2-core CPU "
                   "in minutes: width 8, 32 x 32 patches, batch 8, lr 1e-2, 40 epochs)")
    g.add_argument("--patch", type=int, help="training patch side (paper: 64; a multiple of 16)")
    g.add_argument("--batch", type=int, help="patches per training step (paper: 128)")
    g.add_argument("--lr", type=float, help="Adam's learning rate (paper: 1e-3)")
    g.add_argument("--workers", type=int, default=0,
                   help="DataLoader worker processes (the same batches with any number)")
    g.add_argument("--amp", choices=["bf16"], help="bfloat16 mixed precision (for GPUs)")
    g.add_argument("--channels-last", action="store_true",
                   help="channels-last memory format (for GPUs)")


def resolve(args):
    """Fill ``args.epochs``/``width``/``patch``/``batch``/``lr`` from the preset
    where the command line left them out; returns the training options for Experiment."""
    preset = PRESETS[args.preset or "paper"]
    for k in ("epochs", "width", "patch", "batch", "lr"):
        if getattr(args, k, None) is None:
            setattr(args, k, preset[k])
    return {"patch": args.patch, "batch": args.batch, "lr": args.lr, "amp": args.amp,
            "channels_last": bool(args.channels_last), "workers": args.workers,
            "preset": args.preset}


def config(opts):
    """The options' entries of RUN/config.json (those that are not the paper's), checked."""
    opts = dict(opts or {})
    patch, batch = int(opts.get("patch", 64)), int(opts.get("batch", 128))
    if patch < 16 or patch % 16:
        raise ValueError(f"--patch {patch}: a positive multiple of 16 (the UNet pools 4 times)")
    if batch < 1:
        raise ValueError(f"--batch {batch}: at least 1")
    lr = float(opts.get("lr", 1e-3))
    if not 0 < lr < 1:
        raise ValueError(f"--lr {lr}: between 0 and 1")
    if int(opts.get("workers", 0)) < 0:
        raise ValueError(f"--workers {opts.get('workers')}: at least 0")
    vals = {"patch": patch, "batch": batch, "lr": lr, "amp": opts.get("amp"),
            "channels_last": bool(opts.get("channels_last", False))}
    out = {k: v for k, v in vals.items() if v != DEFAULTS[k]}
    if opts.get("preset"):
        out["preset"] = opts["preset"]
    return out


def apply(cfg, opts):
    """Put the options' config entries into ``cfg`` (an ExperimentError-like ValueError when
    one is bad); returns the loader's worker count (not in the config: it changes no
    number)."""
    cfg.update(config(opts))
    return int((opts or {}).get("workers", 0))
