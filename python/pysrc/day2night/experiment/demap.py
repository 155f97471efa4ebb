"""The report's Delta E 2000 maps (RUN/img/<task>/<row>/<scene>_<input>_de.png) in a perceptual
colour map, and the scale bar the page shows beside them.

The colour map is viridis (van der Walt and Smith, 2015): perceptually uniform, readable in grey
and by the colour-blind, dark at 0 and yellow, never white, at the top, so a large error is not
taken for a missing image on the white page. Its 256 entries are matplotlib's ``_viridis_data``
(lib/matplotlib/_cm_listed.py, released CC0 by its authors) rounded to 8-bit sRGB.

The scale is logarithmic, ``log(1 + dE) / log(1 + DE_MAX)``, clipped at :data:`DE_MAX`: a good
model's errors (below 1 or 2, the paper's means are near 1) and a smoke run's (10 to 40) both
stay visible on one scale, the same for every row and run so maps compare across rows."""

import numpy as np

#: The top of the scale: a Delta E 2000 of DE_MAX or more is the last colour.
DE_MAX = 50.0
#: The values marked on the scale bar.
TICKS = (0, 1, 2, 5, 10, 20, 50)

VIRIDIS = (
    "440154 440256 450457 450559 46075a 46085c 460a5d 460b5e "
    "470d60 470e61 471063 471164 471365 481467 481668 481769 "
    "48186a 481a6c 481b6d 481c6e 481d6f 481f70 482071 482173 "
    "482374 482475 482576 482677 482878 482979 472a7a 472c7a "
    "472d7b 472e7c 472f7d 46307e 46327e 46337f 463480 453581 "
    "453781 453882 443983 443a83 443b84 433d84 433e85 423f85 "
    "424086 424186 414287 414487 404588 404688 3f4788 3f4889 "
    "3e4989 3e4a89 3e4c8a 3d4d8a 3d4e8a 3c4f8a 3c508b 3b518b "
    "3b528b 3a538b 3a548c 39558c 39568c 38588c 38598c 375a8c "
    "375b8d 365c8d 365d8d 355e8d 355f8d 34608d 34618d 33628d "
    "33638d 32648e 32658e 31668e 31678e 31688e 30698e 306a8e "
    "2f6b8e 2f6c8e 2e6d8e 2e6e8e 2e6f8e 2d708e 2d718e 2c718e "
    "2c728e 2c738e 2b748e 2b758e 2a768e 2a778e 2a788e 29798e "
    "297a8e 297b8e 287c8e 287d8e 277e8e 277f8e 27808e 26818e "
    "26828e 26828e 25838e 25848e 25858e 24868e 24878e 23888e "
    "23898e 238a8d 228b8d 228c8d 228d8d 218e8d 218f8d 21908d "
    "21918c 20928c 20928c 20938c 1f948c 1f958b 1f968b 1f978b "
    "1f988b 1f998a 1f9a8a 1e9b8a 1e9c89 1e9d89 1f9e89 1f9f88 "
    "1fa088 1fa188 1fa187 1fa287 20a386 20a486 21a585 21a685 "
    "22a785 22a884 23a983 24aa83 25ab82 25ac82 26ad81 27ad81 "
    "28ae80 29af7f 2ab07f 2cb17e 2db27d 2eb37c 2fb47c 31b57b "
    "32b67a 34b679 35b779 37b878 38b977 3aba76 3bbb75 3dbc74 "
    "3fbc73 40bd72 42be71 44bf70 46c06f 48c16e 4ac16d 4cc26c "
    "4ec36b 50c46a 52c569 54c568 56c667 58c765 5ac864 5cc863 "
    "5ec962 60ca60 63cb5f 65cb5e 67cc5c 69cd5b 6ccd5a 6ece58 "
    "70cf57 73d056 75d054 77d153 7ad151 7cd250 7fd34e 81d34d "
    "84d44b 86d549 89d548 8bd646 8ed645 90d743 93d741 95d840 "
    "98d83e 9bd93c 9dd93b a0da39 a2da37 a5db36 a8db34 aadc32 "
    "addc30 b0dd2f b2dd2d b5de2b b8de29 bade28 bddf26 c0df25 "
    "c2df23 c5e021 c8e020 cae11f cde11d d0e11c d2e21b d5e21a "
    "d8e219 dae319 dde318 dfe318 e2e418 e5e419 e7e419 eae51a "
    "ece51b efe51c f1e51d f4e61e f6e620 f8e621 fbe723 fde725 "
)
#: (256, 3) uint8: the colour of each level 0..255.
LUT = np.array([[int(h[i:i + 2], 16) for i in (0, 2, 4)] for h in "".join(VIRIDIS).split()],
               dtype=np.uint8)


def position(de):
    """Where Delta E ``de`` (array or number) sits on the scale, 0 to 1 (NaN: the top)."""
    d = np.nan_to_num(np.asarray(de, dtype=np.float64), nan=DE_MAX, posinf=DE_MAX)
    return np.log1p(np.clip(d, 0.0, DE_MAX)) / np.log1p(DE_MAX)


def colour(de):
    """A (H, W) Delta E map as a (H, W, 3) uint8 sRGB image in the colour map."""
    return LUT[np.rint(position(de) * 255).astype(np.intp)]


def _hex(level):
    return "#" + "".join(f"{c:02x}" for c in LUT[level])


def scale_bar(width=384, height=14):
    """The scale bar as inline SVG: the colour map from 0 to DE_MAX with its ticks."""
    stops = "".join(f'<stop offset="{i / 32:.4f}" stop-color="{_hex(min(255, i * 8))}"/>'
                    for i in range(33))
    ticks = []
    for v in TICKS:
        x = 4 + float(position(v)) * width
        anchor = "start" if v == TICKS[0] else "end" if v == TICKS[-1] else "middle"
        label = f"{v}+" if v == TICKS[-1] else str(v)
        ticks.append(f'<line x1="{x:.1f}" y1="{height}" x2="{x:.1f}" y2="{height + 4}" '
                     f'stroke="#333"/><text x="{x:.1f}" y="{height + 15}" font-size="11" '
                     f'text-anchor="{anchor}">{label}</text>')
    return (f'<svg class="scale" xmlns="http://www.w3.org/2000/svg" width="{width + 8}" '
            f'height="{height + 18}" role="img" aria-label="Delta E 2000 colour scale, 0 to '
            f'{DE_MAX:g} and more, logarithmic"><defs><linearGradient id="de-scale">{stops}'
            f'</linearGradient></defs><rect x="4" y="0" width="{width}" height="{height}" '
            f'fill="url(#de-scale)" stroke="#333" stroke-width="0.5"/>{"".join(ticks)}</svg>')


def legend():
    """The sentence and scale bar the page shows with the maps."""
    return ('<p class="note">Delta E 2000 maps: colour map viridis, logarithmic scale '
            f"log(1 + &Delta;E), from 0 (dark purple) to {DE_MAX:g} or more (yellow), the "
            f"same scale for every row.</p>{scale_bar()}")
