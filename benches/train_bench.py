"""Benchmarks of the night ISP trainer (day2night.train; issue 31), run by hand, not a test.

    python benches/train_bench.py train  [--features 32] [--batch 128] [--steps 5] [--runs 3]
    python benches/train_bench.py fresh  DAY.dng [--crop 512] [--items 40] [--runs 3] [--train-steps 1] [--images 1]
    python benches/train_bench.py loader DAY.dng [--crop 512] [--items 40] [--batch 128] [--runs 3] [--images 1]
    python benches/train_bench.py cache  DAY.dng [--tiles 6x8] [--runs 3]
    python benches/train_bench.py noise  DAY.dng [--calls 200] [--runs 3]
    python benches/train_bench.py infer  DAY.dng [--features 32] [--tile 512] [--check-features 4]

- train: training steps/s and patches/s of the UNet on CPU (random 64 x 64 patches; the
  first step, which builds the kernels, is not timed); the median over runs.
- fresh: FreshPatches on one core (day2night.set_threads(1), torch.set_num_threads(1)):
  items/s and 64 x 64 patches/s of whole items (one native ``fresh_pair`` call each), next
  to the trainer's consumption on the same machine (training steps/s x batch of the UNet at
  --features, one thread, after the fresh runs; --train-steps 0 skips it); then the numpy
  path of earlier versions on the same items, stage by stage (synthesis, network input,
  sRGB target, cutting). The Rust split of an item: benches/fresh.rs.
- --images N (fresh, loader): the day folder holds N names of the DNG (links), as a
  training set of N images does (the experiment's: 60), and the items are drawn at random
  over them, so each image is decoded again whenever the dataset's per-process cache no
  longer holds it. With 1 (the default) every item reads the same decoded image. fresh
  times its items after the dataset's preload() where it has one (a training run's state
  after its first epoch), the preload itself apart; loader times make_loader apart.
- noise: synthesize(raw, crop=64 px) calls/s on an input whose NoiseProfile is removed
  (ISO known: the noise is estimated from the image) against the same input with it.
- infer: peak RSS of a full-image inference (a child process per run, GNU-time-like
  ru_maxrss) at --features, tiled; then, at the narrow --check-features width (whose whole
  12 MP image fits in memory with the native convolution), the tiled bytes against the
  untiled bytes of the same 12 MP input.

Make a 12 MP input as benches/run.sh does: cargo build --release --example
make_bench_input, then target/release/examples/make_bench_input /tmp/day.dng.
Numbers: docs/benchmarks.md ("Night ISP training").
"""

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def bench_train(a):
    import torch
    from day2night.train.unet import UNet
    torch.manual_seed(0)
    model = UNet(3, 3, a.features)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    x = torch.rand(a.batch, 3, 64, 64)
    y = torch.rand(a.batch, 3, 64, 64)

    def step():
        opt.zero_grad(set_to_none=True)
        loss = torch.nn.functional.l1_loss(model(x), y)
        loss.backward()
        opt.step()

    step()
    rates, cpu = [], []
    for _ in range(a.runs):
        t, c = time.perf_counter(), time.process_time()
        for _ in range(a.steps):
            step()
        rates.append(a.steps / (time.perf_counter() - t))
        cpu.append(a.steps / (time.process_time() - c))
    s = statistics.median(rates)
    return {"bench": "train", "features": a.features, "batch": a.batch,
            "threads": torch.get_num_threads(), "steps_per_s": s, "patches_per_s": s * a.batch,
            "runs": rates, "patches_per_cpu_s": statistics.median(cpu) * a.batch}


def day_folder(dng, images):
    """A temporary folder of ``images`` names (links) of ``dng``: day.dng for one, else
    day000.dng, day001.dng, ..."""
    d = tempfile.mkdtemp()
    names = ["day.dng"] if images == 1 else [f"day{i:03d}.dng" for i in range(images)]
    for n in names:
        os.symlink(os.path.abspath(dng), os.path.join(d, n))
    return d


def bench_fresh(a):
    import random
    import warnings
    import torch
    import day2night
    from day2night.train import data, preprocess, targets
    day2night.set_threads(1)
    torch.set_num_threads(1)
    warnings.simplefilter("ignore")  # one warning per image name otherwise (--images)
    d = day_folder(a.dng, a.images)
    ds = data.FreshPatches(d, crop=a.crop, patch=64, isos=(1600, 3200), seed=0,
                           crops_per_image=10**6)
    ds[0]  # decode the image into the dataset's cache, make its noise estimate
    preload = None
    if hasattr(ds, "preload"):  # the images a training run keeps after its first epoch
        t = time.perf_counter()
        ds.preload()
        preload = time.perf_counter() - t
    # one image: items 1, 2, 3, ...; several: items drawn at random over all the images
    draw = random.Random(0)
    order = (iter(range(1, len(ds))) if a.images == 1
             else (draw.randrange(len(ds)) for _ in iter(int, 1)))
    rates, cpu_rates = [], []
    for _ in range(a.runs):
        t, c = time.perf_counter(), time.process_time()
        for _ in range(a.items):
            ds[next(order)]
        rates.append(a.items / (time.perf_counter() - t))
        cpu_rates.append(a.items / (time.process_time() - c))
    s = statistics.median(rates)
    # per CPU second of the process (all its threads): what a core gives when the machine
    # is shared and the wall clock counts other processes' time too
    res = {"bench": "fresh", "crop": a.crop, "images": a.images, "threads": 1, "items_per_s": s,
           "patches_per_s_per_core": s * ds.patches_per_item, "runs": rates,
           "patches_per_cpu_s": statistics.median(cpu_rates) * ds.patches_per_item,
           "cpu_runs": cpu_rates, "preload_s": preload}
    # the numpy path of earlier versions on the same items, stage by stage
    stages = {"synthesize": [], "input": [], "target": [], "cut": []}
    old, old_cpu = [], []
    for k in range(1, 1 + a.items):
        c0 = time.process_time()
        q = ds.pairs.place(k)
        t0 = time.perf_counter()
        out = day2night.synthesize(q["raw"], seed=0, variant=q["variant"], isos=(q["iso"],),
                                   crop=q["crop"])
        t1 = time.perf_counter()
        x = preprocess.network_input_array(out["noisy"][q["iso"]], q["raw"].meta,
                                           out["neutral"], q["crop"][0], q["crop"][1])
        t2 = time.perf_counter()
        y = targets.srgb8(out["target"])
        t3 = time.perf_counter()
        torch.from_numpy(data.cut(x, 64)), torch.from_numpy(data.cut(y, 64).astype(np.float32) / 255)
        t4 = time.perf_counter()
        for name, dt in zip(stages, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            stages[name].append(dt)
        old.append(t4 - t0)
        old_cpu.append(time.process_time() - c0)
    res["numpy_path"] = {
        "patches_per_s_per_core": ds.patches_per_item / statistics.median(old),
        "patches_per_cpu_s": ds.patches_per_item * len(old_cpu) / sum(old_cpu),
        "stage_ms": {n: 1000 * statistics.median(v) for n, v in stages.items()}}
    if a.train_steps > 0:
        tr = bench_train(argparse.Namespace(features=a.features, batch=a.batch,
                                            steps=a.train_steps, runs=a.runs))
        res["trainer"] = {k: tr[k] for k in ("features", "batch", "threads", "steps_per_s",
                                              "patches_per_s", "runs", "patches_per_cpu_s")}
        res["fresh_over_trainer"] = res["patches_per_s_per_core"] / tr["patches_per_s"]
    return res


def bench_noise(a):
    import warnings
    import day2night
    day2night.set_threads(1)
    warnings.simplefilter("ignore")
    raw = day2night.read_dng(a.dng)
    meta = dict(raw.meta)
    if not meta.get("noise_profile"):
        # an input without one (make_bench_input's): give the "with" case a NoiseProfile
        meta["noise_profile"] = [[2e-5, 1e-7]]
    without = dict(meta, noise_profile=None)
    out = {"bench": "noise", "iso": meta["iso"], "threads": 1}
    for label, m in (("with_noise_profile", meta), ("without_noise_profile", without)):
        r = day2night.Raw.from_array(raw.data, m, name=raw.name)
        day2night.synthesize(r, seed=0, isos=(1600,), crop=(0, 0, 64, 64))  # first call
        rates = []
        for run in range(a.runs):
            t = time.perf_counter()
            for i in range(a.calls):
                day2night.synthesize(r, seed=0, variant=i, isos=(1600,),
                                     crop=(64 * (i % 40), 64 * run, 64, 64))
            rates.append(a.calls / (time.perf_counter() - t))
        out[label + "_calls_per_s"] = statistics.median(rates)
        out[label + "_runs"] = rates
    return out


def _infer_child(a):
    """One inference in this process; prints JSON with the output's hash and peak RSS."""
    import hashlib
    import torch
    import day2night
    from day2night.train import infer, preprocess
    from day2night.train.unet import UNet
    x = preprocess.network_input(day2night.read_dng(a.dng))
    torch.manual_seed(0)
    m = UNet(3, 3, a.features).eval()
    tile = None if a.tile == 0 else a.tile
    t = time.perf_counter()
    y = infer.predict(m, x, tile=tile)
    secs = time.perf_counter() - t
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    print(json.dumps({"features": a.features, "tile": tile, "shape": list(y.shape),
                      "seconds": secs, "peak_rss_bytes": rss,
                      "sha256": hashlib.sha256(y.tobytes()).hexdigest()}))


def _child(a, features, tile):
    r = subprocess.run([sys.executable, __file__, "infer-child", a.dng, "--features",
                        str(features), "--tile", str(tile)], capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"inference child failed: {r.stderr[-3000:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def bench_infer(a):
    runs = [_child(a, a.features, a.tile) for _ in range(a.runs)]
    tiled = _child(a, a.check_features, a.tile)
    whole = _child(a, a.check_features, 0)
    return {"bench": "infer", "features": a.features, "tile": a.tile,
            "peak_rss_gib": statistics.median(r["peak_rss_bytes"] for r in runs) / 2**30,
            "seconds": statistics.median(r["seconds"] for r in runs),
            "runs": runs, "check_features": a.check_features,
            "check_tiled": tiled, "check_untiled": whole,
            "identical": tiled["sha256"] == whole["sha256"]}


def bench_loader(a):
    """Patches/s of the training loader of "Ours, fresh synthesis" (``trainer.make_loader``
    over ``FreshPatches``, --crop crops, batches of --batch patches) with 0, 1 and 2 worker
    processes, each over the same --items items of one epoch (median of --runs); then the
    trainer's own consumption (training steps/s x batch at --features, this process's
    torch threads) unless --train-steps 0."""
    import warnings
    import torch
    from day2night.train import data, trainer
    warnings.simplefilter("ignore")  # one warning per image name otherwise (--images)
    d = day_folder(a.dng, a.images)
    counts = [a.items // a.images + (i < a.items % a.images) for i in range(a.images)]

    def dataset():
        return data.FreshPatches(d, crop=a.crop, patch=64, isos=(1600, 3200), seed=0,
                                 items_per_image=counts)

    out = {"bench": "loader", "crop": a.crop, "items": a.items, "images": a.images,
           "batch": a.batch, "patches_per_item": dataset().patches_per_item, "workers": {}}
    for workers in (0, 1, 2):
        # a new dataset for each worker count: none starts with the images that the
        # previous count decoded; what make_loader prepares is timed apart
        ds = dataset()
        cfg = trainer.TrainConfig(out_dir=d, batch_size=a.batch, workers=workers)
        t = time.perf_counter()
        loader, sampler = trainer.make_loader(ds, cfg, 0, 1, shuffle=True)
        prepare = time.perf_counter() - t
        rates = []
        for run in range(a.runs):
            sampler.set_epoch(run)
            ds.set_epoch(run)
            t, n = time.perf_counter(), 0
            for x, _ in loader:
                n += x.shape[0]
            rates.append(n / (time.perf_counter() - t))
        out["workers"][workers] = {"patches_per_s": statistics.median(rates), "runs": rates,
                                   "make_loader_s": prepare}
        print(f"workers {workers}: {statistics.median(rates):.0f} patches/s", file=sys.stderr)
    if a.train_steps:
        a.steps, a.runs = a.train_steps, 1
        out["trainer"] = bench_train(a)
    return out


def bench_cache(a):
    """The input store (day2night.train.cache) of the network input of the DNG's active area
    tiled --tiles (an even tile keeps the CFA phase; 512 x 512 x 6 x 8 is 12.6 MP): bytes per
    pixel against float32's 12, encode, full decode and per-patch decode times (one thread,
    median of --runs), and whether the bits come back."""
    import day2night
    from day2night.train import cache, preprocess
    raw = day2night.read_dng(a.dng)
    ty, tx = (int(v) for v in a.tiles.split("x"))
    plane = np.tile(preprocess.active_plane(raw), (ty, tx))
    x = preprocess.network_input_array(plane, raw.meta)
    h, w = x.shape[:2]
    enc, dec, win = [], [], []
    for _ in range(a.runs):
        t = time.perf_counter()
        e = cache.encode(x)
        enc.append(time.perf_counter() - t)
        t = time.perf_counter()
        d = cache.decode(e)
        dec.append(time.perf_counter() - t)
        t = time.perf_counter()
        for k in range(200):
            cache.decode_window(e, 64 * (k % (h // 64)), 64 * (k // (h // 64) % (w // 64)), 64, 64)
        win.append((time.perf_counter() - t) / 200)
    return {"bench": "cache", "size": [w, h], "megapixels": w * h / 1e6,
            "encoding": cache.ENCODINGS[cache.info(e)["encoding"]],
            "bytes_per_pixel": e.nbytes / (w * h), "float32_bytes_per_pixel": x.nbytes / (w * h),
            "exact": bool(np.array_equal(d.view(np.uint32), x.view(np.uint32))),
            "encode_s": statistics.median(enc), "decode_s": statistics.median(dec),
            "patch64_decode_ms": 1e3 * statistics.median(win)}


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("what", choices=("train", "fresh", "loader", "cache", "noise", "infer",
                                      "infer-child"))
    p.add_argument("dng", nargs="?")
    p.add_argument("--features", type=int, default=32)
    p.add_argument("--check-features", type=int, default=4)
    p.add_argument("--batch", type=int, default=128)
    p.add_argument("--steps", type=int, default=5)
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--crop", type=int, default=512)
    p.add_argument("--items", type=int, default=40)
    p.add_argument("--images", type=int, default=1,
                   help="fresh, loader: names (links) of the DNG in the day folder")
    p.add_argument("--train-steps", type=int, default=1)
    p.add_argument("--calls", type=int, default=200)
    p.add_argument("--tile", type=int, default=512)
    p.add_argument("--tiles", default="6x8", help="cache: the input tiled rows x columns")
    a = p.parse_args()
    if a.what != "train" and not a.dng:
        p.error(f"{a.what} needs a DNG")
    if a.what == "infer-child":
        return _infer_child(a)
    res = {"train": bench_train, "fresh": bench_fresh, "loader": bench_loader, "cache": bench_cache,
           "noise": bench_noise, "infer": bench_infer}[a.what](a)
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
