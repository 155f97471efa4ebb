"""The numpy implementation of the release's noise the experiment had before it called the
extension's (``day2night._native.release_noise``: src/noise/release.rs), kept as the oracle
of test_release_noise.py: the same bytes, and its own copy of the S20 FE table, which
test_release_noise.py compares with the extension's.

The authors' ``prepare_data.py`` adds noise to every synthetic clean night raw with its S20 FE
table (``noise_profiler/h-gauss-s20-v1``), whatever the camera of the day image, in DN with
the black level included, and then clips to [0, 1023] and truncates to integers:

    var = beta1[p] * x + beta2[p]     (x: the clean raw in DN, p: the 2x2 position of the
                                       visible raw; computed in float32, negative -> 0)
    noisy = uint16(clip(float32(x + sqrt(var) * z), 0, 1023)),  z ~ N(0, 1) (float64)

``DN_TABLE`` holds the table's figures (the same numbers as the ``dn_table`` of the project's
calibration/samsung-s20fe/noise.json, which the Rust synthesis embeds; a test checks that the
two agree): derived from the CVPR 2022 day-to-night release, CC BY-NC 4.0.

Only the visible area (the ActiveArea) gets noise; the masked border keeps its samples. The
normal draws are ``numpy.random.RandomState(key).normal`` (the release's generator and
method) with a key from the experiment seed, the day image and the ISO, so a run is
deterministic; the release's own draws are unseeded. For a camera whose white level is not
1023 the clip at 1023 is applied all the same (the release does), which saturates anything
brighter: the experiment says so."""

import hashlib

import numpy as np

CLIP_MAX = 1023
DN_TABLE = {
    100: ((0.1419234149084682, -8.890307111076448), (0.14010851348394535, -8.684474895126055),
          (0.13982037914173523, -8.685826036688809), (0.1418040808370286, -8.868374099147276)),
    200: ((0.28459846397296595, -17.99830279350811), (0.2842019999864774, -17.908969030282638),
          (0.28228803918683115, -17.791730955968337), (0.2840307985544278, -17.913387024217805)),
    400: ((0.5645075071356364, -35.755209362962496), (0.5623994898053915, -35.57701376873653),
          (0.5584229215509176, -35.23834418320569), (0.5631269260866636, -35.62237948220208)),
    800: ((1.1212485582585008, -69.87470804123991), (1.1213600816123324, -69.79704865646038),
          (1.1139926392926753, -69.33176850507408), (1.119083971640854, -69.49979993675758)),
    1600: ((2.2435579560800636, -134.13813652456366), (2.2318542023898225, -132.79735744428996),
           (2.212563286375087, -131.45865250865327), (2.233160798965846, -132.7768160221999)),
    3200: ((4.292001197640824, -234.9049461133207), (4.216130811900908, -228.34061839150064),
           (4.185857471741983, -226.2369996301509), (4.295593457145119, -235.7195457993698)),
}


def noise_key(seed, name, iso):
    """The RandomState key of one noisy image: SHA-256 of (seed, image, ISO) as 8 words."""
    digest = hashlib.sha256(f"day2night release noise v1|{int(seed)}|{name}|{int(iso)}"
                            .encode("utf-8")).digest()
    return np.frombuffer(digest, dtype="<u4")


def add_release_noise(plane, iso, rng):
    """The release's noisy raw of a clean ``plane`` (2-D, DN, the visible raw: its 2x2
    positions are the table's) at ``iso`` (a calibrated ISO of ``DN_TABLE``), drawing from
    ``rng`` (a ``numpy.random.RandomState``). Returns uint16."""
    if int(iso) not in DN_TABLE:
        raise ValueError(f"ISO {iso}: the release's S20 FE table has "
                         f"{', '.join(map(str, sorted(DN_TABLE)))}")
    image = np.asarray(plane).astype(np.float32)
    if image.ndim != 2:
        raise ValueError(f"a CFA plane must be 2-D, got shape {image.shape}")
    var = np.zeros(image.shape, np.float64)
    for p, (b1, b2) in enumerate(DN_TABLE[int(iso)]):
        i, j = divmod(p, 2)
        # float32 sample times a scalar stays float32, as in the release
        var[i::2, j::2] = image[i::2, j::2] * np.float32(b1) + np.float32(b2)
    var[var < 0] = 0
    noise = rng.normal(loc=0, scale=1, size=image.shape) * np.sqrt(var)
    noisy = (image + noise).astype(np.float32)
    return np.clip(noisy, 0, CLIP_MAX).astype(np.uint16)


def release_noisy_plane(stored, active_area, iso, key):
    """The whole stored plane with its active area replaced by the release's noisy raw."""
    t, l, b, r = (int(v) for v in active_area)
    out = np.array(stored, dtype=np.uint16, copy=True)
    rng = np.random.RandomState(key)
    out[t:b, l:r] = add_release_noise(out[t:b, l:r], iso, rng)
    return out
