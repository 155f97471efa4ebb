#!/usr/bin/env python3
"""Write compressed DNG test files with tifffile + imagecodecs (independent of day2night).

usage: make_compressed_dngs.py OUT_DIR

Writes into OUT_DIR, for each NAME, NAME.dng and NAME.bin: the samples the file must decode
to (little-endian uint16, row-major, samples interleaved), which are the array the generator
wrote for lossless files and tifffile's (libjpeg) decode for lossy ones:

  cfa_jxl_tiles      16-bit RGGB CFA, lossless JPEG XL (52546) tiles 128x128, 400x300
                     (edge tiles cropped), ActiveArea and DefaultCrop
  cfa_jxl_strips     the same pixels in lossless JPEG XL strips of 64 rows (last strip 44)
  linear_jxl_tiles   16-bit LinearRaw (3 samples), lossless JPEG XL tiles 128x128, per-sample
                     BlackLevel and WhiteLevel
  linear_jxl_lossy   the linear_jxl_tiles pixels in lossy JPEG XL (distance 1, XYB/VarDCT)
  linear_jpeg_tiles  8-bit LinearRaw, lossy JPEG (34892) tiles 128x128, quality 90, YCbCr
                     4:4:4 (no chroma subsampling, so decoders agree to a code or two)
  bad_jxl_tile_size  as cfa_jxl_tiles, but tile 1's codestream is 64x64: must be refused
  bad_cfa_jpeg       8-bit CFA in lossy JPEG strips: the specification allows lossy JPEG
                     for LinearRaw only (the Adobe DNG SDK refuses it): must be refused

Every lossless file is checked here too: tifffile's decode equals the written array.
Prints one line per file; exits 1 on any mismatch.
"""
import os
import sys

import imagecodecs
import numpy as np
import tifffile

W, H, TILE = 400, 300, 128


def srational(vals):
    out = []
    for v in vals:
        out += [int(round(v * 10000)), 10000]
    return out


def rational(vals):
    out = []
    for v in vals:
        out += [int(round(v * 10000)), 10000]
    return out


def dng_tags(model, cfa, black, white, black_repeat=(1, 1)):
    """Extra tags of a minimal valid DNG 1.7 raw IFD0 (tifffile writes the structure)."""
    # XYZ(D65) -> camera of an sRGB-like camera (inverse sRGB primaries).
    cm = [3.2404542, -1.5371385, -0.4985314, -0.9692660, 1.8760108, 0.0415560,
          0.0556434, -0.2040259, 1.0572252]
    tags = [
        (50706, "B", 4, (1, 7, 0, 0), True),  # DNGVersion
        (50707, "B", 4, (1, 4, 0, 0), True),  # DNGBackwardVersion
        (271, "s", 0, "day2night", True),  # Make
        (272, "s", 0, model, True),  # Model
        (50708, "s", 0, "day2night " + model, True),  # UniqueCameraModel
        (50713, "H", 2, black_repeat, True),  # BlackLevelRepeatDim
        (50714, "H", len(black), tuple(black), True),  # BlackLevel
        (50717, "H", len(white), tuple(white), True),  # WhiteLevel
        (50721, "2i", 9, tuple(srational(cm)), True),  # ColorMatrix1
        (50778, "H", 1, (21,), True),  # CalibrationIlluminant1 D65
        (50728, "2I", 3, tuple(rational([0.55, 1.0, 0.7])), True),  # AsShotNeutral
        (274, "H", 1, (1,), True),  # Orientation
        (50829, "I", 4, (2, 4, H - 2, W - 4), True),  # ActiveArea
        (50719, "2I", 2, (2, 1, 2, 1), True),  # DefaultCropOrigin
        (50720, "2I", 2, (W - 16, 1, H - 12, 1), True),  # DefaultCropSize
    ]
    if cfa:
        tags += [
            (33421, "H", 2, (2, 2), True),  # CFARepeatPatternDim
            (33422, "B", 4, (0, 1, 1, 2), True),  # CFAPattern RGGB
            (50710, "B", 3, (0, 1, 2), True),  # CFAPlaneColor
            (50711, "H", 1, (1,), True),  # CFALayout
        ]
    return tags


def scene(h, w, channels, maxval, seed):
    """A smooth colour scene with noise and a few saturated and black pixels."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    base = 0.5 + 0.4 * np.sin(x / 23.0) * np.cos(y / 31.0)
    out = []
    for c in range(channels):
        v = base * (0.6 + 0.2 * c) + 0.05 * rng.standard_normal((h, w))
        out.append(np.clip(v, 0, 1) * maxval)
    a = np.stack(out, axis=-1) if channels > 1 else out[0]
    a = np.round(a).astype(np.uint16 if maxval > 255 else np.uint8)
    a[5, 7] = maxval
    a[6, 8] = 0
    return a


def write(path, data, photometric, compression, tags, tile=None, rowsperstrip=None,
          compressionargs=None, shape=None, dtype=None):
    kw = dict(
        photometric=photometric,
        compression=compression,
        compressionargs=compressionargs,
        extratags=tags,
        subfiletype=0,
        planarconfig="contig",
    )
    if tile:
        kw["tile"] = tile
    if rowsperstrip:
        kw["rowsperstrip"] = rowsperstrip
    if shape is not None:
        kw["shape"] = shape
        kw["dtype"] = dtype
    tifffile.imwrite(path, data, **kw)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    bad = 0

    def save(name, expected, lossless):
        nonlocal bad
        path = os.path.join(out, name + ".dng")
        got = tifffile.TiffFile(path).pages[0].asarray()
        if lossless and not np.array_equal(got, expected):
            bad += 1
            print("FAIL", name, "tifffile decode differs from the written array")
        decoded = expected if lossless else got
        decoded.astype("<u2").tofile(os.path.join(out, name + ".bin"))
        print("ok  ", name, decoded.shape, decoded.dtype,
              "lossless (tifffile decode equals the written array)" if lossless
              else "lossy (expected = tifffile decode)")

    cfa16 = scene(H, W, 1, 65535, 1)
    cfa16[cfa16 < 1024] = 1024  # black 1024 (one pixel stays 0: below black is legal)
    cfa16[6, 8] = 0
    jxl = dict(lossless=True)
    tags = dng_tags("JXL CFA", True, [1024], [65535])
    write(os.path.join(out, "cfa_jxl_tiles.dng"), cfa16, 32803, 52546, tags,
          tile=(TILE, TILE), compressionargs=jxl)
    save("cfa_jxl_tiles", cfa16, True)
    write(os.path.join(out, "cfa_jxl_strips.dng"), cfa16, 32803, 52546, tags,
          rowsperstrip=64, compressionargs=jxl)
    save("cfa_jxl_strips", cfa16, True)

    lin16 = scene(H, W, 3, 60000, 2)
    tags = dng_tags("JXL LinearRaw", False, [100, 200, 300], [60000, 61000, 62000])
    write(os.path.join(out, "linear_jxl_tiles.dng"), lin16, 34892, 52546, tags,
          tile=(TILE, TILE), compressionargs=jxl)
    save("linear_jxl_tiles", lin16, True)
    write(os.path.join(out, "linear_jxl_lossy.dng"), lin16, 34892, 52546, tags,
          tile=(TILE, TILE), compressionargs=dict(distance=1.0))
    save("linear_jxl_lossy", lin16, False)

    lin8 = scene(H, W, 3, 255, 3)
    tags = dng_tags("lossy LinearRaw", False, [0, 0, 0], [255, 255, 255])
    write(os.path.join(out, "linear_jpeg_tiles.dng"), lin8, 34892, 34892, tags,
          tile=(TILE, TILE), compressionargs=dict(level=90, subsampling="444"))
    save("linear_jpeg_tiles", lin8, False)

    cfa8 = scene(H, W, 1, 255, 4)
    tags = dng_tags("lossy CFA", True, [8], [255])
    write(os.path.join(out, "bad_cfa_jpeg.dng"), cfa8, 32803, 34892, tags,
          rowsperstrip=64, compressionargs=dict(level=90))
    print("ok   bad_cfa_jpeg (lossy JPEG CFA)")

    # Pre-encoded tiles (tifffile writes them as given): tile 1 holds a 64x64 codestream.
    tiles = []
    for ty in range(0, H, TILE):
        for tx in range(0, W, TILE):
            t = np.zeros((TILE, TILE), np.uint16)
            part = cfa16[ty:ty + TILE, tx:tx + TILE]
            t[: part.shape[0], : part.shape[1]] = part
            if len(tiles) == 1:
                t = t[:64, :64]
            tiles.append(imagecodecs.jpegxl_encode(np.ascontiguousarray(t), lossless=True))
    tags = dng_tags("JXL CFA", True, [1024], [65535])
    write(os.path.join(out, "bad_jxl_tile_size.dng"), iter(tiles), 32803, 52546, tags,
          tile=(TILE, TILE), shape=(H, W), dtype=np.uint16)
    print("ok   bad_jxl_tile_size (tile 1 is 64x64)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
