#!/usr/bin/env python3
"""Check a day2night illuminant dictionary's fitted Gaussian against numpy.

usage: calibrate_gaussian_check.py ILLUMINANTS.json
Recomputes mean and covariance of [r/g, b/g] over `illuminants_rgb_over_g` with numpy
(np.cov, unbiased or bias=True for "maximum_likelihood") and compares with the file's `fit` (rtol 1e-9).
Exit 0 when equal, 1 with the differences otherwise.
"""
import json
import sys

import numpy as np


def main():
    d = json.load(open(sys.argv[1]))
    pts = np.array(d["illuminants_rgb_over_g"], dtype=float)
    fails = []
    if d["count"] != len(pts) or d["fit"]["count"] != len(pts):
        fails.append(f"count {d['count']} / fit count {d['fit']['count']} vs {len(pts)} illuminants")
    if not np.allclose(pts[:, 1], 1.0):
        fails.append("green component is not 1")
    rb = pts[:, [0, 2]]
    mean = rb.mean(axis=0)
    est = d["fit"]["estimator"]
    if est not in ("unbiased", "maximum_likelihood"):
        fails.append(f"unknown estimator {est!r}")
    if len(pts) == 1:
        cov = np.zeros((2, 2))  # documented fallback: one illuminant, zero covariance
    else:
        cov = np.cov(rb.T, bias=(est == "maximum_likelihood"))
    if not np.allclose(d["fit"]["mean"], mean, rtol=1e-9, atol=1e-12):
        fails.append(f"mean {d['fit']['mean']} vs numpy {mean.tolist()}")
    if not np.allclose(d["fit"]["covariance"], cov, rtol=1e-9, atol=1e-15):
        fails.append(f"covariance {d['fit']['covariance']} vs numpy {cov.tolist()}")
    if fails:
        print("\n".join(fails))
        sys.exit(1)
    print(f"ok: {len(pts)} illuminants, {est} covariance matches numpy")


if __name__ == "__main__":
    main()
