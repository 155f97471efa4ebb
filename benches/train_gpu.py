"""The night ISP on a GPU (issue 35 item 6): training steps/s, patches/s and peak memory of
the paper's UNet (width 32, batches of 128 patches of 64 x 64), then the time and peak
memory of one full-image inference of a 12 MP input (4032 x 3024).

    python benches/train_gpu.py                       # cuda when torch sees one, else cpu
    python benches/train_gpu.py --amp bf16 --channels-last
    python benches/train_gpu.py --tiny                # seconds on a CPU (the tests run it)

Prints one line per measurement and, last, a JSON object with every number. Timings are
medians over ``--runs`` runs of ``--steps`` steps after one untimed warm-up step (CUDA
synchronized around each run). Peak memory: ``torch.cuda.max_memory_allocated`` per phase
on a GPU; on a CPU the process's peak resident set so far (``ru_maxrss``: the inference
figure includes the training phase's peak when that was higher). The data are random
tensors: the network's cost does not depend on the pixels. Numbers: docs/benchmarks.md,
"Night ISP training"."""

import argparse
import json
import resource
import statistics
import sys
import time


def parse(argv):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--device", help="cuda or cpu (default: cuda when available)")
    p.add_argument("--width", type=int, default=32, help="UNet init_features (paper: 32)")
    p.add_argument("--batch", type=int, default=128, help="patches per step (paper: 128)")
    p.add_argument("--patch", type=int, default=64)
    p.add_argument("--steps", type=int, default=20, help="timed steps per run")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--amp", choices=["bf16"], help="bfloat16 autocast")
    p.add_argument("--channels-last", action="store_true")
    p.add_argument("--infer", default="4032x3024", help="inference image WxH ('' skips it)")
    p.add_argument("--tile", default=None,
                   help="inference tile: auto, none or a multiple of 16 (default: none on a "
                   "GPU, auto on a CPU)")
    p.add_argument("--tiny", action="store_true",
                   help="width 4, batch 4, 2 steps x 1 run, 96 x 64 inference (CPU tests)")
    a = p.parse_args(argv)
    if a.tiny:
        a.width, a.batch, a.steps, a.runs, a.infer = 4, 4, 2, 1, "96x64"
    return a


def _peak(torch, device):
    if device.type == "cuda":
        return torch.cuda.max_memory_allocated(device)
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _sync(torch, device):
    if device.type == "cuda":
        torch.cuda.synchronize(device)


def bench_train(torch, a, device):
    from day2night.train.trainer import TrainConfig, autocast, make_model, to_device

    cfg = TrainConfig(out_dir=".", init_features=a.width, amp=a.amp,
                      channels_last=a.channels_last)
    model = make_model(cfg).to(device)
    if a.channels_last:
        model = model.to(memory_format=torch.channels_last)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    x = to_device(torch.rand(a.batch, 3, a.patch, a.patch), device, cfg)
    y = torch.rand(a.batch, 3, a.patch, a.patch, device=device)

    def step():
        opt.zero_grad(set_to_none=True)
        with autocast(cfg, device):
            p = model(x)
        torch.nn.functional.l1_loss(p.float(), y).backward()
        opt.step()

    if device.type == "cuda":
        torch.cuda.reset_peak_memory_stats(device)
    step()
    rates = []
    for _ in range(a.runs):
        _sync(torch, device)
        t = time.perf_counter()
        for _ in range(a.steps):
            step()
        _sync(torch, device)
        rates.append(a.steps / (time.perf_counter() - t))
    s = statistics.median(rates)
    return {"steps_per_s": s, "patches_per_s": s * a.batch, "runs": rates,
            "peak_bytes": _peak(torch, device)}


def bench_infer(torch, a, device):
    import numpy as np

    from day2night.train.infer import predict
    from day2night.train.unet import UNet

    w, h = (int(v) for v in a.infer.lower().split("x"))
    torch.manual_seed(0)
    model = UNet(3, 3, a.width).to(device).eval()
    x = np.random.default_rng(0).random((h, w, 3), dtype=np.float32)
    tile = a.tile or ("auto" if device.type == "cpu" else "none")
    tile = None if tile == "none" else (tile if tile == "auto" else int(tile))
    if device.type == "cuda":
        torch.cuda.reset_peak_memory_stats(device)
    _sync(torch, device)
    t = time.perf_counter()
    out = predict(model, x, tile=tile, device=device, amp=a.amp,
                  channels_last=a.channels_last)
    _sync(torch, device)
    secs = time.perf_counter() - t
    assert out.shape == (h, w, 3) and out.dtype == np.uint8
    return {"size": [w, h], "megapixels": w * h / 1e6, "tile": tile, "seconds": secs,
            "peak_bytes": _peak(torch, device)}


def main(argv=None):
    a = parse(argv)
    import torch

    device = torch.device(a.device or ("cuda" if torch.cuda.is_available() else "cpu"))
    name = torch.cuda.get_device_name(device) if device.type == "cuda" else "cpu"
    res = {"device": str(device), "device_name": name, "torch": torch.__version__,
           "threads": torch.get_num_threads(), "width": a.width, "batch": a.batch,
           "patch": a.patch, "amp": a.amp, "channels_last": a.channels_last, "tiny": a.tiny}
    tr = bench_train(torch, a, device)
    res["train"] = tr
    print(f"train ({name}, width {a.width}, batch {a.batch} of {a.patch}x{a.patch}, amp "
          f"{a.amp or 'off'}, channels_last {a.channels_last}): {tr['steps_per_s']:.3f} "
          f"steps/s, {tr['patches_per_s']:.1f} patches/s, peak {tr['peak_bytes'] / 2**30:.2f} GiB",
          flush=True)
    if a.infer:
        inf = bench_infer(torch, a, device)
        res["infer"] = inf
        print(f"inference {inf['size'][0]}x{inf['size'][1]} ({inf['megapixels']:.1f} MP, tile "
              f"{inf['tile']}): {inf['seconds']:.2f} s, peak {inf['peak_bytes'] / 2**30:.2f} GiB",
              flush=True)
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
