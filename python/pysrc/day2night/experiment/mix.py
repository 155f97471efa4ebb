"""Synthetic + x % real training lists (the paper's "Ours 95 % + Real 5 %" rows).

The release's convention (``mix_synth_real_data.py``): a fold has ``n`` training slots (its
training scenes, in order). ``round(x * n / 100)`` of them stay real; a seeded permutation of
the ``n`` positions is drawn and the first ``n - round(x * n / 100)`` positions are replaced by
the synthetic training item at the same position. Validation stays the fold's real scenes.

Conventions stated in docs/experiment.md:

- ``round`` is Python's (half to even), as in the release; 5 % of 60 is 3, 10 % is 6.
- The permutation is ``numpy.random.RandomState(seed).permutation(n)``; the release's seed is
  101, so with the release's fold lists the same real scenes survive.
- A synthetic slot's white balance is the synthetic image's average night illuminant (the
  release replaces its AsShotNeutral by ``avg_night_illuminant``): ``wb: "avg_night"``.
- Noisy task: slot ``i`` uses ISO 1600 when ``i`` is even and 3200 when odd (the release
  alternates the real lists this way; day2night alternates the synthetic ones too, where the
  release draws each synthetic image's ISO at random).
- With fewer synthetic items than slots, slot ``i`` takes synthetic item ``i mod len``.
"""

import numbers

import numpy as np

from ..isos import NOISY_ISOS

RELEASE_SEED = 101


class MixError(ValueError):
    """A mix that cannot be made (the message names the value)."""


def check_percent(percent):
    """The percentage as a float in [0, 100], else MixError naming it."""
    if isinstance(percent, bool) or not isinstance(percent, numbers.Real):
        raise MixError(f"mix percentage {percent!r} is not a number (use 0 to 100)")
    p = float(percent)
    if not (0.0 <= p <= 100.0):
        raise MixError(f"mix percentage {percent!r} is outside 0-100")
    return p


def real_count(percent, n):
    """How many of ``n`` training slots stay real at ``percent`` % (the release's rounding)."""
    return int(round(check_percent(percent) * n / 100))


def iso_of(position):
    """Noisy task ISO of a list position: even 1600, odd 3200."""
    return NOISY_ISOS[position % 2]


def mix(train, synth, percent, seed=RELEASE_SEED):
    """Training slots of a fold at ``percent`` % real.

    ``train``: the fold's real training scene ids (in the fold manifest's order);
    ``synth``: the synthetic training items (day image names, sorted).
    Returns one dict per slot, in slot order: ``{"slot", "kind": "real"|"synthetic", "id",
    "iso", "wb"}`` where ``iso`` is the noisy task's ISO of the slot and ``wb`` is
    ``"as_shot"`` (real) or ``"avg_night"`` (synthetic)."""
    n = len(train)
    keep = real_count(percent, n)
    if n == 0:
        raise MixError("a mix needs at least one training slot (the fold's training list is empty)")
    replace = n - keep
    if replace and not synth:
        raise MixError(
            f"{percent} % real of {n} slots needs {replace} synthetic items; none were given"
        )
    perm = np.random.RandomState(seed).permutation(n)
    replaced = set(int(i) for i in perm[:replace])
    slots = []
    for i in range(n):
        if i in replaced:
            item = {"kind": "synthetic", "id": str(synth[i % len(synth)]), "wb": "avg_night"}
        else:
            item = {"kind": "real", "id": str(train[i]), "wb": "as_shot"}
        item.update(slot=i, iso=iso_of(i))
        slots.append(item)
    return slots


def synthetic_slots(synth):
    """All-synthetic training or validation slots (the rows trained on synthesis only)."""
    return [
        {"slot": i, "kind": "synthetic", "id": str(s), "iso": iso_of(i), "wb": "avg_night"}
        for i, s in enumerate(synth)
    ]


def real_slots(scenes):
    """All-real slots (supervised training, and every fold's validation list)."""
    return [
        {"slot": i, "kind": "real", "id": str(s), "iso": iso_of(i), "wb": "as_shot"}
        for i, s in enumerate(scenes)
    ]


def split_day_images(names, train=60):
    """The release's split of the day images: sorted, the first ``train`` train, the rest
    validation (70 images: 60 / 10). With fewer images, one in seven (at least one) goes to
    validation."""
    names = sorted(str(n) for n in names)
    if len(names) < 2:
        raise MixError(
            f"synthetic training needs at least 2 day images (train and validation); "
            f"got {len(names)}"
        )
    k = train if len(names) > train else len(names) - max(1, int(round(len(names) / 7)))
    return names[:k], names[k:]
