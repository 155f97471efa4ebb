#!/usr/bin/env python3
"""Independent checks of a night burst written by `day2night synth --burst N`, read with
rawpy (LibRaw) and numpy only.

usage:
  burst_check.py stats SIDECAR.json OUTDIR ISO
      (a --motion none burst) every frame's noise (frame - clean DNG) has the model's
      variance within 3 % (the plan's (S, O) per 2x2 position plus 1/12 DN^2 of rounding,
      over sites whose clean value is 6 sigma inside [0, white], so no clipping), a mean
      within 3 standard errors of 0, and |correlation| < 0.01 with every other frame's.
  burst_check.py merge SIDECAR.json OUTDIR ISO MERGED.dng
      the `day2night merge` of the frames: its mean frame (the sums / N) minus the clean
      DNG has |mean| < 0.05 DN and 1/N of one frame's noise variance within 10 %.
  burst_check.py phase SIDECAR.json OUTDIR ISO WINDOW
      (a shaken burst of a noise-free camera) phase correlation between frame 00 and each
      frame over the central WINDOW x WINDOW samples recovers the displacement the plan
      records at the window's centre (affine(c) - c) within 0.1 px. The estimate is
      refined iteratively (frame k is moved back by the estimate with a cubic spline and the
      residual re-estimated) on the mosaics with each 2x2 position's gain equalized and a
      sigma-1 Gaussian blur, by cross-correlation (skimage's phase_cross_correlation with
      normalization=None, upsampled 200x), so the estimate is not pulled towards 0 by the
      window.
Prints one line per check; exits 1 if any check failed.
"""
import json
import os
import sys

import numpy as np

FAILS = []


def fail(msg):
    FAILS.append(msg)
    print("FAIL", msg)


def ok(msg):
    print("ok  ", msg)


def visible(path):
    import rawpy

    with rawpy.imread(path) as r:
        return r.raw_image_visible.astype(np.float64), int(r.white_level)


def frames(sc, outdir, iso):
    base = sc["outputs"]["files"][0][: -len("_clean.dng")]
    n = sc["plan"]["burst"]["frames"]
    return [os.path.join(outdir, f"{base}_iso{iso}_f{k:02d}.dng") for k in range(n)], base


def stats(sidecar, outdir, iso):
    import rawpy

    sc = json.load(open(sidecar))
    paths, base = frames(sc, outdir, iso)
    cpath = os.path.join(outdir, base + "_clean.dng")
    with rawpy.imread(cpath) as r:
        clean = r.raw_image_visible.astype(np.float64)
        white = float(r.white_level)
        blacks = np.array(r.black_level_per_channel, dtype=np.float64)
        colors = r.raw_colors_visible.copy()
        pattern = r.raw_pattern.copy()
    # black per site (LibRaw's channel indices)
    black = blacks[colors]
    scale = white - blacks.max()
    entry = [e for e in sc["plan"]["noise"] if e["iso"] == iso][0]
    pos = np.array(entry["params"]["positions"], dtype=np.float64)
    h, w = clean.shape
    p = (np.arange(h)[:, None] % 2) * 2 + (np.arange(w)[None, :] % 2)
    y = (clean - black) / scale
    var = np.maximum(0.0, pos[p, 0] * y + pos[p, 1]) * scale * scale + 1.0 / 12.0
    sd = np.sqrt(var)
    keep = (clean - 6 * sd > 0) & (clean + 6 * sd < white) & (var > 1.0)
    if keep.sum() < 10000:
        fail(f"only {keep.sum()} unclipped sites")
        return
    noise = []
    for k, path in enumerate(paths):
        f, _ = visible(path)
        d = (f - clean)[keep]
        noise.append(d)
        ratio = (d * d).sum() / var[keep].sum()
        se = d.std() / np.sqrt(d.size)
        if abs(ratio - 1) > 0.03:
            fail(f"frame {k:02d}: noise variance / model {ratio:.4f} (outside 3 %)")
        else:
            ok(f"frame {k:02d}: noise variance / model {ratio:.4f} over {d.size} sites")
        if abs(d.mean()) > 3 * se + 1e-9:
            fail(f"frame {k:02d}: noise mean {d.mean():.4f} DN (3 s.e. {3 * se:.4f})")
    worst = 0.0
    for a in range(len(noise)):
        for b in range(a + 1, len(noise)):
            c = np.corrcoef(noise[a], noise[b])[0, 1]
            worst = max(worst, abs(c))
            if abs(c) >= 0.01:
                fail(f"frames {a:02d} and {b:02d}: noise correlation {c:.4f}")
    ok(f"largest |noise correlation| between frames {worst:.4f}")


def merge(sidecar, outdir, iso, merged):
    import rawpy

    sc = json.load(open(sidecar))
    paths, base = frames(sc, outdir, iso)
    n = len(paths)
    clean, white = visible(os.path.join(outdir, base + "_clean.dng"))
    with rawpy.imread(merged) as r:
        m = r.raw_image_visible.astype(np.float64)
        mwhite = float(r.white_level)
    k = mwhite / white
    mean_frame = m / k
    f0, _ = visible(paths[0])
    # unclipped sites of every frame: the clean value 6 of one frame's sigmas inside
    one = f0 - clean
    sd = np.sqrt(np.maximum(one.var(), 1e-9))
    keep = (clean > 6 * sd) & (clean < white - 6 * sd)
    d = (mean_frame - clean)[keep]
    bias = d.mean()
    vf = np.mean([((visible(p)[0] - clean)[keep]).var() for p in paths])
    ratio = d.var() / (vf / n)
    print(f"merged: scale {k:g}, bias {bias:.4f} DN, variance {d.var():.3f} vs one frame {vf:.3f} / {n}")
    if abs(bias) >= 0.05:
        fail(f"merge bias {bias:.4f} DN (>= 0.05)")
    else:
        ok(f"merge bias {bias:.4f} DN")
    if abs(ratio - 1) > 0.10:
        fail(f"merge variance x N / frame variance {ratio:.4f} (outside 10 %)")
    else:
        ok(f"merge variance is 1/{n} of a frame's (ratio {ratio:.4f})")


def phase(sidecar, outdir, iso, window):
    from scipy.ndimage import gaussian_filter, shift as ndshift
    from skimage.registration import phase_cross_correlation

    sc = json.load(open(sidecar))
    paths, _ = frames(sc, outdir, iso)
    tr = sc["plan"]["burst"]["transforms"]

    def img(p):
        v, _ = visible(p)
        for i in range(2):
            for j in range(2):
                v[i::2, j::2] /= max(v[i::2, j::2].mean(), 1e-9)
        return gaussian_filter(v, 1.0)

    g0 = img(paths[0])
    h, w = g0.shape
    s = window
    y0, x0 = (h - s) // 2, (w - s) // 2
    cx, cy = x0 + (s - 1) / 2.0, y0 + (s - 1) / 2.0
    han = np.outer(np.hanning(s), np.hanning(s))

    def win(im):
        a = im[y0:y0 + s, x0:x0 + s]
        return (a - a.mean()) * han

    worst = 0.0
    for k in range(1, len(paths)):
        gk = img(paths[k])
        est = np.zeros(2)
        for _ in range(5):
            back = ndshift(gk, est, order=3, mode="nearest")
            sh, _, _ = phase_cross_correlation(win(g0), win(back), upsample_factor=200,
                                               normalization=None)
            est = est + sh
        a = np.array(tr[k]["affine"])
        want = a @ np.array([cx, cy, 1.0]) - np.array([cx, cy])
        got = np.array([-est[1], -est[0]])
        err = np.abs(got - want).max()
        worst = max(worst, err)
        line = f"frame {k:02d}: displacement ({got[0]:.3f}, {got[1]:.3f}) vs recorded ({want[0]:.3f}, {want[1]:.3f})"
        if err > 0.1:
            fail(line + f": error {err:.3f} px")
        else:
            ok(line)
    ok(f"largest displacement error {worst:.3f} px")


def main():
    mode = sys.argv[1]
    if mode == "stats":
        stats(sys.argv[2], sys.argv[3], int(sys.argv[4]))
    elif mode == "merge":
        merge(sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5])
    elif mode == "phase":
        phase(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]))
    else:
        fail(f"unknown mode {mode}")
    if FAILS:
        print(f"{len(FAILS)} check(s) failed")
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()
