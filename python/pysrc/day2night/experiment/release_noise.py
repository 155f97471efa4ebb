"""The release's noise on synthetic noisy inputs (``--noise release``), computed by the
extension (``day2night._native.release_noise``: src/noise/release.rs).

The authors' ``prepare_data.py`` adds noise to every synthetic clean night raw with its S20 FE
table (``noise_profiler/h-gauss-s20-v1``), whatever the camera of the day image, in DN with
the black level included, and then clips to [0, 1023] and truncates to integers:

    var = beta1[p] * x + beta2[p]     (x: the clean raw in DN, p: the 2x2 position of the
                                       visible raw; computed in float32, negative -> 0)
    noisy = uint16(clip(float32(x + sqrt(var) * z), 0, 1023)),  z ~ N(0, 1) (float64)

``DN_TABLE`` holds the table's figures, read from the extension: the ``dn_table`` of the
project's calibration/samsung-s20fe/noise.json, which the Rust synthesis embeds (its one
copy): derived from the CVPR 2022 day-to-night release, CC BY-NC 4.0.

Only the visible area (the ActiveArea) gets noise; the masked border keeps its samples. The
normal draws are ``numpy.random.RandomState(key).normal``'s (the release's generator and
method; the extension draws them from the generator's state, bit for bit) with a key from
the experiment seed, the day image and the ISO, so a run is deterministic; the release's
own draws are unseeded. For a camera whose white level is not 1023 the clip at 1023 is
applied all the same (the release does), which saturates anything brighter: the experiment
says so."""

import hashlib

import numpy as np

from .._native import RELEASE_NOISE_TABLE, release_noise

CLIP_MAX = 1023


def _dn_table(rows):
    out = {}
    for iso, pos, b1, b2 in sorted(rows):
        out.setdefault(int(iso), [None] * 4)[int(pos)] = (b1, b2)
    return {iso: tuple(v) for iso, v in out.items()}


#: {ISO: ((beta1, beta2) of positions 0..3)}: the extension's table.
DN_TABLE = _dn_table(RELEASE_NOISE_TABLE["rows"])


def noise_key(seed, name, iso):
    """The RandomState key of one noisy image: SHA-256 of (seed, image, ISO) as 8 words."""
    digest = hashlib.sha256(f"day2night release noise v1|{int(seed)}|{name}|{int(iso)}"
                            .encode("utf-8")).digest()
    return np.frombuffer(digest, dtype="<u4")


def add_release_noise(plane, iso, rng):
    """The release's noisy raw of a clean ``plane`` (2-D, DN, the visible raw: its 2x2
    positions are the table's) at ``iso`` (a calibrated ISO of ``DN_TABLE``), drawing from
    ``rng`` (a ``numpy.random.RandomState``, advanced as its ``normal`` would be). Returns
    uint16."""
    if int(iso) not in DN_TABLE:
        raise ValueError(f"ISO {iso}: the release's S20 FE table has "
                         f"{', '.join(map(str, sorted(DN_TABLE)))}")
    image = np.asarray(plane).astype(np.float32)
    if image.ndim != 2:
        raise ValueError(f"a CFA plane must be 2-D, got shape {image.shape}")
    name, *state = rng.get_state(legacy=True)
    noisy, state = release_noise(image, int(iso), tuple(state))
    rng.set_state((name, *state))
    return noisy


def release_noisy_plane(stored, active_area, iso, key):
    """The whole stored plane with its active area replaced by the release's noisy raw."""
    t, l, b, r = (int(v) for v in active_area)
    out = np.array(stored, dtype=np.uint16, copy=True)
    rng = np.random.RandomState(key)
    out[t:b, l:r] = add_release_noise(out[t:b, l:r], iso, rng)
    return out
