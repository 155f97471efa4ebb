"""day2night.train: the paper's night ISP (a UNet, Sec. 4.1 of the paper and the authors'
release), trained on day2night's pairs and scored as the release scores it.

Install with ``pip install day2night[train]`` (PyTorch). ``import day2night`` never imports
torch; this package imports it only for the modules that need it:

- ``preprocess`` (numpy): the release's network input of a raw;
- ``targets`` (numpy): day2night's linear targets to the 8-bit sRGB of the PNG targets;
- ``scores`` (numpy): PSNR, SSIM (the release's conventions) and mean Delta E 2000;
- ``unet``, ``data``, ``trainer``, ``infer`` (torch): the network, patch sets, training
  (``TrainConfig``, ``train``; ``python -m day2night.train``, torchrun for several
  processes) and full-image inference.

The names below are imported on first use (``day2night.train.train`` imports torch,
``day2night.train.network_input`` does not). See docs/python.md, "Night ISP training".
"""

import importlib

_NAMES = {
    "network_input": "preprocess",
    "network_input_array": "preprocess",
    "demosaic_bilinear": "preprocess",
    "GAMMA": "preprocess",
    "srgb8": "targets",
    "render_target": "targets",
    "score": "scores",
    "score_set": "scores",
    "UNet": "unet",
    "parameter_count": "unet",
    "FixedPatches": "data",
    "FreshPatches": "data",
    "save_pair": "data",
    "TrainConfig": "config",
    "train": "trainer",
    "load_model": "trainer",
    "predict": "infer",
    "predict_float": "infer",
    "write_png": "infer",
}

__all__ = sorted(_NAMES)


def __getattr__(name):
    mod = _NAMES.get(name)
    if mod is None:
        raise AttributeError(f"module 'day2night.train' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{mod}", __name__), name)
