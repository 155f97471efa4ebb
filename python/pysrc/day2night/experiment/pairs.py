"""Network input / target pairs of the experiment, made once and cached in the run folder.

- Real scene (test time, and real training slots): the clean task's input is the merged clean
  raw preprocessed with its own AsShotNeutral; the noisy task's input is the ISO's first
  frame, also with its AsShotNeutral; the target is the real-pairs PNG.
- Synthetic item (a day image of DAY_DIR): ``day2night.synthesize`` in the row's mode (``day``,
  ``dimmed``, ``global`` or ``local``), the network input preprocessed with the night neutral
  the synthesis reports (the average night illuminant under local relighting: the release's
  ``--wb-illum avg``), the target the clean night raw rendered with the same neutral.

Each pair is stored as ``<name>.in.npy`` (the input in ``day2night.train.cache``'s exact
store: 14-bit CFA codes, about 2 bytes per pixel) and ``<name>.y.npy`` (uint8 H x W x 3),
written through a temporary file + rename; an existing pair is reused. A pair of the first
cache format (``<name>.x.npy``, float32 H x W x 3) is migrated on first use: stored again,
checked bit for bit, and the old file removed."""

import io
import pathlib

import numpy as np

import day2night

from ..isos import NOISY_ISOS
from ..train import cache as input_cache
from ..train.preprocess import GAMMA
from ..atomic import write_bytes
from ..png import read_png
from ..train.preprocess import network_input
from ..train.targets import render_target, srgb8
from .release_noise import noise_key, release_noisy_plane
from ..variants import Geometry, Isp, Noise



#: The gamma id of every input a run writes (the release's 1/2.2: preprocess.network_input).
RUN_GAMMA_ID = input_cache.gamma_id(GAMMA)


class PairError(ValueError):
    """A pair that cannot be made (the message names the scene or file)."""


def _npy_bytes(a):
    buf = io.BytesIO()
    np.save(buf, a, allow_pickle=False)
    return buf.getvalue()


def cached(folder, names, make):
    """{key: (x_path, y_path)} of stored pairs named ``names[key]``; ``make() -> {key: (x, y)}``
    runs when any of them is absent (one synthesis gives every key of a day image). ``x_path``
    is the ``.in.npy`` store: read it with ``load``."""
    folder = pathlib.Path(folder)
    paths = {k: (folder / f"{n}.in.npy", folder / f"{n}.y.npy") for k, n in names.items()}
    for xp, yp in paths.values():
        _migrate(xp, yp)
    if not all(xp.is_file() and yp.is_file() for xp, yp in paths.values()):
        made = make()
        for k, (xp, yp) in paths.items():
            x, y = made[k]
            # y first: x present means the pair is complete
            write_bytes(yp, _npy_bytes(np.ascontiguousarray(y, np.uint8)))
            write_bytes(xp, _npy_bytes(input_cache.encode(x)))
    return paths


def _migrate(xp, yp):
    """An input of the first format (``<name>.x.npy``, float32) stored again as ``xp``."""
    old = xp.with_name(xp.name[: -len(".in.npy")] + ".x.npy")
    if xp.is_file() or not (old.is_file() and yp.is_file()):
        return
    try:
        x = np.load(old, allow_pickle=False)
    except (OSError, ValueError) as e:
        raise PairError(f"{old}: an input of the first cache format that cannot be read "
                        f"({e}); delete it to have it made again") from None
    if x.dtype != np.float32 or x.ndim != 3 or x.shape[2] != 3:
        raise PairError(f"{old}: {x.dtype} {x.shape} is not a float32 H x W x 3 input of the "
                        "first cache format; delete it to have it made again")
    if not (np.isfinite(x).all() and x.min(initial=0) >= 0 and x.max(initial=0) <= 1):
        raise PairError(f"{old}: an input of the first cache format holding values that are "
                        "not finite or outside [0, 1] (a run writes neither); delete it to "
                        "have it made again")
    enc = input_cache.encode(x)
    if not np.array_equal(input_cache.decode(enc).view(np.uint32), x.view(np.uint32)):
        raise PairError(f"{old}: migrating it did not give the same bits")  # pragma: no cover
    write_bytes(xp, _npy_bytes(enc))
    old.unlink()


def load(path):
    """A stored array: the float32 H x W x 3 input of an ``.in.npy`` store, else the array
    itself (memory-mapped)."""
    a = np.load(path, mmap_mode="r", allow_pickle=False)
    if input_cache.is_encoded(a):
        return input_cache.decode(a, str(path))
    return a


def check_cached(xp, yp):
    """A cached pair whose input store and uint8 H x W x 3 target agree (for the run-folder
    checks): a ValueError whose message starts with the damaged file's path and says
    "damaged cached array". Returns (H, W)."""
    try:
        head = input_cache.info(np.load(xp, mmap_mode="r", allow_pickle=False), str(xp))
    except (OSError, ValueError, EOFError) as e:
        raise ValueError(f"{xp}: damaged cached array ({_first_line(e)})") from None
    try:
        y = np.load(yp, mmap_mode="r", allow_pickle=False)
    except (OSError, ValueError, EOFError) as e:
        raise ValueError(f"{yp}: damaged cached array ({_first_line(e)})") from None
    if head["encoding"] == input_cache.FLOAT32 or head["gamma_id"] != RUN_GAMMA_ID:
        raise ValueError(
            f"{xp}: damaged cached array: a {input_cache.ENCODINGS[head['encoding']]} store "
            f"with gamma id {head['gamma_id']}; a run writes 14-bit codes on the release's "
            f"1/2.2 table (gamma id {RUN_GAMMA_ID})")
    hw = (head["height"], head["width"])
    if y.dtype != np.uint8 or y.shape != (*hw, 3):
        raise ValueError(f"{yp}: damaged cached array: {y.dtype} {y.shape}, expected uint8 "
                         f"{hw[0]} x {hw[1]} x 3 (its input {xp.name})")
    return hw


def _first_line(e):
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def _read_dng(path, what):
    try:
        return day2night.read_dng(str(path))
    except (OSError, ValueError) as e:
        raise PairError(f"{what}: cannot read {path}: {e}") from None


def _input_raw(scene, task_iso):
    if task_iso is None:
        return _read_dng(scene.clean_raw, f"scene {scene.id}")
    if task_iso not in scene.noisy:
        raise PairError(f"scene {scene.id}: no ISO {task_iso} input")
    return _read_dng(scene.noisy[task_iso], f"scene {scene.id}")


def real_pair(scene, task_iso, targets=None, source=None):
    """(x, y) of a real scene: ``task_iso`` None for the clean task, else the noisy ISO.

    ``targets``: the run's ISP (``"release"`` or ``"day2night"``; None: the real-pairs PNG,
    its geometry told by its shape, as before ``--targets``); ``source``: the ISP that made the
    scene's PNG (protocol.scene_target_isp). The PNG is used when it came from ``targets``'
    ISP (and, for day2night's, from a clean raw without opcode lists, which its render
    applies); otherwise the target is rendered again from the scene's clean raw by
    :func:`real_target`. The input is then cut and turned onto the target's pixel grid."""
    raw = _input_raw(scene, task_iso)
    x = network_input(raw)
    y, geometry = real_target(scene, targets, source)
    aligned = align(x, y, raw.meta, geometry)
    if aligned is None:
        how = GEOMETRY_TEXT.get(geometry, "neither its DefaultCrop + Orientation nor a quarter "
                                "turn")
        raise PairError(
            f"scene {scene.id}: target {scene.target} is {y.shape[1]}x{y.shape[0]}; the "
            f"network input of {raw.file_name} is {x.shape[1]}x{x.shape[0]} (active area), "
            f"and {how} matches the target"
        )
    return aligned


GEOMETRY_TEXT = {
    Geometry.RAW: "the active area itself",
    Geometry.RENDER: "neither its DefaultCrop + Orientation nor a quarter turn",
    Geometry.RELEASE: "neither the release's crop + orientation nor a quarter turn",
}


def has_opcodes(meta):
    """Whether a raw's metadata holds a non-empty DNG opcode list."""
    return any(meta.get(f"opcode_list{i}") for i in (1, 2, 3))


def real_target(scene, targets, source):
    """(uint8 target, geometry) of a real scene for the run's ``targets`` ISP (see
    :func:`real_pair`)."""
    if targets is None:
        return read_png(scene.target), None
    if source == targets == Isp.RELEASE:
        return read_png(scene.target), Geometry.RELEASE
    clean = _read_dng(scene.clean_raw, f"scene {scene.id}")
    if source == targets == Isp.DAY2NIGHT and not has_opcodes(clean.meta):
        return read_png(scene.target), Geometry.RENDER
    # neutral None: the clean raw's own AsShotNeutral, read as each ISP reads it (the
    # release's as stored)
    return render_target_as(targets, clean, None, display=True)


def render_target_as(isp, raw, neutral, display):
    """(uint8 target, geometry) of ``raw`` rendered by ``isp`` with white balance ``neutral``,
    DNG opcode lists ignored on every path (the network input never applies them; the
    release ignores them too). ``display``: day2night's target in the geometry real-pairs
    writes (DefaultCrop, Orientation: geometry "render"), else the active area as stored
    (geometry "raw"). The release's ISP has one geometry, its own ("release")."""
    if isp == Isp.RELEASE:
        return release_render(raw, neutral), Geometry.RELEASE
    if isp != Isp.DAY2NIGHT:
        raise PairError(f"targets {isp!r}: use release or day2night")
    rgb = day2night.render(raw, neutral=neutral, demosaic="mhc", crop=display, orient=display,
                           opcodes="ignore")
    return srgb8(rgb), (Geometry.RENDER if display else Geometry.RAW)


def release_render(raw, neutral):
    """The release ISP's 8-bit target of ``raw`` (``render --isp release``: its crop and its
    orientation, opcode lists ignored)."""
    return np.asarray(render_target(raw, neutral=neutral, isp=Isp.RELEASE), np.uint8)


def orient(img, orientation):
    """``img`` (H, W, ...) displayed as the TIFF/Exif Orientation tag (1..8) says."""
    o = int(orientation or 1)
    t = np.swapaxes(img, 0, 1)
    return {
        1: img,
        2: img[:, ::-1],
        3: img[::-1, ::-1],
        4: img[::-1],
        5: t,
        6: t[:, ::-1],
        7: t[::-1, ::-1],
        8: t[::-1],
    }.get(o, img)


def release_orient(img, orientation):
    """``img`` turned as the release's ``fix_orientation`` turns it: as the Exif tag for 1, 3,
    6 and 8, but 2 flips top to bottom and 4 left to right (OpenCV's flip codes 0 and 1), and
    5 and 7 are each other's Exif turn (transverse and transpose)."""
    o = int(orientation or 1)
    swapped = {2: 4, 4: 2, 5: 7, 7: 5}
    return orient(img, swapped.get(o, o))


def release_window(meta, height, width):
    """(top, left, height, width) of the active area (``height`` x ``width``) that the
    release's render keeps: rawpy's visible image (the ActiveArea), cropped once more by
    ``active_area_cropping`` with the ActiveArea's own numbers (unless they are
    ``[0, 0, height, width]``), as numpy slicing clips them."""
    area = meta.get("active_area")
    if not area or [int(v) for v in area] == [0, 0, height, width]:
        return 0, 0, height, width
    t, l, b, r = (int(v) for v in area)
    rows = range(height)[t:b]
    cols = range(width)[l:r]
    return t, l, len(rows), len(cols)


def _default_crop(x, meta):
    crop = meta.get("default_crop")
    if not crop:
        return None
    top, left, h, w = (int(round(float(v))) for v in crop)
    return x[top : top + h, left : left + w]


def _candidates(x, y, meta, geometry):
    """The ways ``x`` (active area, stored orientation) may sit on ``y``'s pixel grid, most
    likely first: each an (x', y') pair."""
    o = meta.get("orientation")
    if geometry == Geometry.RAW:
        return [(x, y)]
    out = []
    if geometry in (None, Geometry.RENDER):
        xc = _default_crop(x, meta)
        if xc is not None:
            out.append((orient(xc, o), y))
        out.append((orient(x, o), y))  # a render without the DefaultCrop
    if geometry in (None, Geometry.RELEASE):
        t, l, h, w = release_window(meta, *x.shape[:2])
        out.append((release_orient(x[t : t + h, l : l + w], o), y))
    # a target that is the active area turned a quarter (the release's portrait PNGs, which
    # its test.py turns back)
    out.append((x, np.rot90(y)))
    return out


def align(x, y, meta, geometry=None):
    """(x, y) on one pixel grid, or None. The network input ``x`` covers the active area in
    sensor orientation; ``geometry`` says how the target ``y`` was made:

    - ``"raw"``: the active area as stored (``render(crop=False, orient=False)``);
    - ``"render"``: day2night's default render (what real-pairs writes): ``x`` is cut to the
      DefaultCrop and turned by the Orientation (whatever the shapes: a flip or a half turn
      keeps them), or only turned when the target has no DefaultCrop;
    - ``"release"``: the release's render: ``x`` is cut to :func:`release_window` and turned
      by :func:`release_orient`;
    - None: the first of those whose shape matches (the shape check of the real set).

    A target that is the active area turned a quarter (the release's portrait targets) is
    turned back, as the release's test.py does."""
    for xa, ya in _candidates(x, y, meta, geometry):
        if xa.shape == ya.shape:
            return np.ascontiguousarray(xa), np.ascontiguousarray(ya)
    return None


def synth_pairs(day_path, mode, seed, isos=NOISY_ISOS, targets=Isp.DAY2NIGHT,
                noise=Noise.DAY2NIGHT):
    """{key: (x, y)} of one day image synthesized in ``mode``: key ``"clean"`` and each ISO.

    ``targets``: the ISP of the target (day2night's, with opcodes ignored like the input,
    or the release's); ``noise``: the noisy inputs' noise (``"day2night"``: the synthesis'
    own model; ``"release"``: release_noise.py on the clean night raw)."""
    day = _read_dng(day_path, "day image")
    own_isos = tuple(isos) if noise == Noise.DAY2NIGHT else ()
    try:
        out = day2night.synthesize(day, seed=seed, mode=mode, isos=own_isos, target=None)
    except ValueError as e:
        raise PairError(f"{day_path}: synthesis ({mode}) failed: {e}") from None
    neutral = tuple(float(v) for v in out["neutral"])
    meta = dict(day.meta)
    meta["as_shot_neutral"] = list(neutral)
    clean = day2night.Raw.from_array(out["clean"], meta, name=day.name)
    y, geometry = render_target_as(targets, clean, neutral, display=False)
    planes = {"clean": out["clean"]}
    for iso in isos:
        if noise == Noise.RELEASE:
            planes[iso] = release_noisy_plane(out["clean"], day.meta["active_area"], iso,
                                              noise_key(seed, day.name, iso))
        else:
            planes[iso] = np.asarray(out["noisy"][iso])
    pairs = {}
    for key, plane in planes.items():
        raw = clean if key == "clean" else day2night.Raw.from_array(plane, meta, name=day.name)
        pair = align(network_input(raw, neutral=neutral), y, meta, geometry)
        if pair is None:
            raise PairError(f"{day_path}: the {targets} target does not cover the network "
                            "input's pixel grid")
        pairs[key] = pair
    return pairs
