"""day2night: night raw synthesis for training night-mode neural ISPs, in Python.

Fresh, seeded night pairs are synthesized in memory, on the crops a training step uses,
with the same numbers as the ``day2night synth`` command line (the Rust library does the
work, with the GIL released).

>>> import day2night
>>> raw = day2night.read_dng("day.dng")
>>> out = day2night.synthesize(raw, seed=0, isos=(1600,), crop=(0, 0, 512, 512))
>>> out["noisy"][1600].shape, out["target"].shape
((512, 512), (512, 512, 3))

``NightPairs`` is a map-style dataset for ``torch.utils.data.DataLoader`` (no torch import
here). Raws from other sources: ``Raw.from_array(data, meta, name=...)``, ``from_rawpy``
(any camera raw rawpy reads) and ``write_dng``. See docs/python.md of the repository.
``dataset_units``, ``write_unit``/``write_units`` (``group_units``: one task per input) and
``write_manifest`` run ``day2night dataset`` as independent units on a scheduler such as Ray
Data (python/examples/ray_dataset.py).
"""

from ._native import (  # noqa: F401
    BOUNDS,
    Raw,
    Synthesis,
    check_int,
    delta_e2000,
    delta_e2000_map,
    demosaic_bilinear,
    encode_u8,
    png_bytes,
    png_decode,
    merge,
    psnr,
    read_dng,
    release_codes,
    render,
    set_threads,
    ssim,
    threads,
    version,
    write_dng,
    write_manifest,
    write_outputs,
)
from . import diagnostics  # noqa: F401
from .diagnostics import (  # noqa: F401
    WARNING_CLASSES,
    WARNING_CODES,
    Day2NightWarning,
    warning_class,
)
from .pairs import NightPairs, pack_bayer  # noqa: F401
from .rawpy_meta import from_rawpy  # noqa: F401
from .units import group_units  # noqa: F401
from . import _native, signatures

# The synthesis functions with the signatures the option table gives them
# (``inspect.signature`` lists every option with its default: signatures.py).
synthesize = signatures.signed(_native.synthesize)
night_pair = signatures.signed(_native.night_pair)
write_unit = signatures.signed(_native.write_unit)
write_units = signatures.signed(_native.write_units)
dataset_units = signatures.signed(_native.dataset_units)
signatures.sign_class(NightPairs)

__version__ = version()

# One Day2NightWarning subclass per warning code (NoiseExtrapolatedWarning, ...).
globals().update({c.__name__: c for c in WARNING_CLASSES.values()})

__all__ = [
    "BOUNDS",
    "Day2NightWarning",
    "NightPairs",
    "Raw",
    "Synthesis",
    "check_int",
    "dataset_units",
    "delta_e2000",
    "delta_e2000_map",
    "demosaic_bilinear",
    "encode_u8",
    "from_rawpy",
    "group_units",
    "merge",
    "night_pair",
    "pack_bayer",
    "png_bytes",
    "png_decode",
    "psnr",
    "read_dng",
    "release_codes",
    "render",
    "set_threads",
    "ssim",
    "synthesize",
    "threads",
    "version",
    "write_dng",
    "write_manifest",
    "write_outputs",
    "write_unit",
    "write_units",
    "WARNING_CLASSES",
    "WARNING_CODES",
    "warning_class",
] + sorted(c.__name__ for c in WARNING_CLASSES.values())
