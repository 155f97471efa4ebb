"""Full-image inference of the night ISP, as the release's test.py runs it: the whole
network input at once, the output clipped to [0, 1] and ``(255 * y)`` truncated to uint8.

The input is padded (reflected) to a multiple of 16, the UNet's pooling factor, and the
output cut back. ``tile=T`` runs the same computation in T x T tiles (T a multiple of 16)
with a ``halo`` of context on each side (default: the UNet's receptive-field radius rounded
up to 16, ``unet.receptive_radius``): tiles start on the 16-grid, so every pooling window
and every convolution that reaches a kept pixel sees what it sees in the whole image, and
the kept pixels are the untiled ones (a test checks the bytes). Peak memory then scales
with the tile, not the image. Inference runs PyTorch's native CPU convolution (oneDNN
off): oneDNN chooses its kernels by tensor size, which changes the last bit of some
outputs between a tile and the whole image, and a truncated byte with it.
"""

import contextlib

import numpy as np

from ..png import write_png  # noqa: F401  (the package's one PNG writer)
from ._torch import torch
from .unet import UNet, receptive_radius

M = UNet.MULTIPLE


def default_halo():
    r = receptive_radius()
    return -(-r // M) * M


def _pad(x):
    h, w = x.shape[:2]
    ph, pw = -h % M, -w % M
    if ph or pw:
        mode = "reflect" if h > ph and w > pw else "edge"
        x = np.pad(x, ((0, ph), (0, pw), (0, 0)), mode=mode)
    return x


def _run(model, x, device, exact, amp=None, channels_last=False):
    t = torch.from_numpy(np.ascontiguousarray(x.transpose(2, 0, 1)))[None].to(device)
    if channels_last:
        model.to(memory_format=torch.channels_last)
        t = t.contiguous(memory_format=torch.channels_last)
    dev = torch.device(device).type
    cast = (torch.autocast(device_type=dev, dtype=torch.bfloat16) if amp == "bf16"
            else contextlib.nullcontext())
    # exact: PyTorch's own CPU convolution (oneDNN off) and cuDNN without autotuning. oneDNN
    # picks its kernels by tensor size, so a tile and the whole image can differ in the last
    # bit (and then in a truncated byte); the native path gives the same bits for both.
    with torch.no_grad(), torch.backends.mkldnn.flags(enabled=not exact), \
            torch.backends.cudnn.flags(enabled=True, benchmark=False, deterministic=exact), cast:
        y = model(t)
    return y[0].float().permute(1, 2, 0).contiguous().cpu().numpy()


#: Images up to this many pixels run whole under ``tile="auto"``; larger ones in tiles of
#: ``AUTO_TILE`` (the native convolution's im2col buffer grows with the tile: 64 channels x
#: 9 x pixels x 4 bytes, 1.25 GB for a 512 tile with its halo at width 32).
AUTO_WHOLE = 1 << 20
AUTO_TILE = 512


def predict_float(model, x, tile="auto", halo=None, device=None, exact=True, amp=None,
                  channels_last=False):
    """The network's float output (H x W x 3) for the network input ``x`` (H x W x 3).

    ``tile``: ``"auto"`` (whole up to 1 MP, else 512), None (whole) or a multiple of 16.
    ``exact=False`` lets PyTorch use oneDNN (faster on CPU; tiles may then differ from the
    whole image in the last bit). ``amp="bf16"``: the forward in bfloat16 autocast;
    ``channels_last``: NHWC memory format (both for GPUs; close to, not equal to, float32:
    python/tests/test_train_amp.py states the tolerance)."""
    x = np.asarray(x, dtype=np.float32)
    if x.ndim != 3 or x.shape[2] != 3:
        raise ValueError(f"the network input must be H x W x 3, got {x.shape}")
    if device is None:
        device = next(model.parameters()).device
    model.eval()
    h, w = x.shape[:2]
    xp = _pad(x)
    H, W = xp.shape[:2]
    if tile == "auto":
        tile = None if H * W <= AUTO_WHOLE else AUTO_TILE
    if tile is None or (tile >= H and tile >= W):
        return _run(model, xp, device, exact, amp, channels_last)[:h, :w]
    if tile % M or tile < M:
        raise ValueError(f"tile {tile} must be a positive multiple of {M}")
    halo = default_halo() if halo is None else int(halo)
    if halo % M:
        raise ValueError(f"halo {halo} must be a multiple of {M}")
    out = np.empty((H, W, 3), dtype=np.float32)
    for top in range(0, H, tile):
        for left in range(0, W, tile):
            t0, l0 = max(0, top - halo), max(0, left - halo)
            t1, l1 = min(H, top + tile + halo), min(W, left + tile + halo)
            y = _run(model, xp[t0:t1, l0:l1], device, exact, amp, channels_last)
            bh, bw = min(tile, H - top), min(tile, W - left)
            out[top:top + bh, left:left + bw] = y[top - t0:top - t0 + bh, left - l0:left - l0 + bw]
    return out[:h, :w]


def to_u8(y):
    """The release's output quantization: clip to [0, 1], ``(255 * y)`` truncated."""
    return (255 * np.clip(y, 0, 1)).astype(np.uint8)


def predict(model, x, tile="auto", halo=None, device=None, exact=True, amp=None,
            channels_last=False):
    """uint8 H x W x 3 sRGB prediction of the network input ``x`` (``preprocess``): the
    release's quantization of ``predict_float``."""
    return to_u8(predict_float(model, x, tile, halo, device, exact, amp, channels_last))


