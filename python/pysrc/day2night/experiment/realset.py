"""The real night pairs written by ``day2night real-pairs SCENES -o OUT`` (docs/experiment.md):

    OUT/manifest.jsonl                    one JSON record per scene ("kind": "real", "scene")
    OUT/real/clean_raw/<id>.dng           merged clean raw (the first low-ISO frame's metadata)
    OUT/real/noisy_raw/<id>_iso<ISO>.dng  first frame of each high-ISO burst
    OUT/real/target/<id>.png              8-bit sRGB target
    OUT/real/meta/<id>.json               per-scene record

Records are read from the manifest's ``outputs`` (kind + path); every file named there must
exist. A failed record, a missing file or a scene without an ISO the task needs is an error
naming the scene and the file. :func:`check_scene` then checks the files themselves before
the experiment writes anything: each output's size and SHA-256 against the manifest's
``bytes`` and ``sha256``, the DNGs the tasks read (``day2night.read_dng``), and the target PNG
(readable, and of the size of the network input cut and turned as the pairing does)."""

import dataclasses
import hashlib
import json
import pathlib
import re

import numpy as np

import day2night

from . import pairs
from ..png import PngError, check_png

NOISY_RE = re.compile(r"_iso(\d+)\.dng$", re.IGNORECASE)


class RealSetError(ValueError):
    """A real set that cannot be used (the message names the file or scene)."""


@dataclasses.dataclass
class RealScene:
    id: str
    clean_raw: pathlib.Path
    target: pathlib.Path
    noisy: dict  # ISO -> pathlib.Path
    frames: dict  # ISO (str) -> frame count, as the manifest records it
    #: (path, bytes, sha256) of every output the manifest lists, as it records them
    outputs: list = dataclasses.field(default_factory=list)


REMAKE = "make the real set again with `day2night real-pairs SCENES -o REAL_DIR`"


def _records(manifest):
    try:
        text = manifest.read_text(encoding="utf-8")
    except OSError as e:
        raise RealSetError(
            f"{manifest}: cannot read the real set's manifest ({e.strerror or e}); "
            "make the real set with `day2night real-pairs SCENES -o REAL_DIR`"
        ) from None
    lines = text.split("\n")
    torn = not text.endswith("\n") and lines[-1] != ""
    out = []
    for i, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            out.append(json.loads(line))
        except ValueError as e:
            if torn and i == len(lines):
                break  # a torn last line of an interrupted run
            raise RealSetError(f"{manifest}: line {i} is not JSON ({e})") from None
    return out


def read_real(real_dir, isos=()):
    """The scenes of a real set, sorted by id. ``isos``: noisy ISOs every scene must have."""
    root = pathlib.Path(real_dir)
    if not root.is_dir():
        raise RealSetError(f"{root}: the real set folder does not exist")
    manifest = root / "manifest.jsonl"
    scenes = {}
    for rec in _records(manifest):
        if not isinstance(rec, dict):
            raise RealSetError(f"{manifest}: a record is not a JSON object: {str(rec)[:60]}")
        if rec.get("kind", "real") != "real":
            continue
        sid = rec.get("scene")
        if not isinstance(sid, str) or not sid:
            raise RealSetError(f"{manifest}: a record has no scene id (input {rec.get('input')!r})")
        if rec.get("status") != "ok":
            raise RealSetError(
                f"{manifest}: scene {sid} failed in real-pairs: {rec.get('error', 'no reason given')}"
            )
        if sid in scenes:
            raise RealSetError(f"{manifest}: scene {sid} is listed twice")
        scenes[sid] = _scene(root, manifest, sid, rec, isos)
    if not scenes:
        raise RealSetError(f"{manifest}: no real scene in the manifest")
    return [scenes[k] for k in sorted(scenes)]


def _output_path(root, manifest, sid, o):
    rel = o.get("path") if isinstance(o, dict) else None
    if not isinstance(rel, str) or not rel or pathlib.PurePosixPath(rel).is_absolute() \
            or ".." in pathlib.PurePosixPath(rel).parts:
        raise RealSetError(f"{manifest}: scene {sid}: an output without a path inside the "
                           f"real set: {str(o)[:80]}")
    path = root / rel
    if not path.is_file():
        raise RealSetError(f"scene {sid}: {path} is listed in the manifest but missing")
    return path


def _scene(root, manifest, sid, rec, isos):
    clean = target = None
    noisy, outputs = {}, []
    listed = rec.get("outputs", [])
    for o in listed if isinstance(listed, list) else [listed]:
        path = _output_path(root, manifest, sid, o)
        outputs.append((path, o.get("bytes"), o.get("sha256")))
        kind = o.get("kind")
        if kind == "clean_raw":
            clean = path
        elif kind == "target":
            if path.suffix.lower() == ".png":
                target = path
        elif kind == "noisy_raw":
            m = NOISY_RE.search(path.name)
            if not m:
                raise RealSetError(f"scene {sid}: noisy raw {path} is not named <id>_iso<ISO>.dng")
            noisy[int(m.group(1))] = path
    if clean is None:
        raise RealSetError(f"scene {sid}: no clean_raw output in {manifest}")
    if target is None:
        raise RealSetError(f"scene {sid}: no PNG target output in {manifest}")
    for iso in isos:
        if iso not in noisy:
            have = ", ".join(str(i) for i in sorted(noisy)) or "none"
            raise RealSetError(
                f"scene {sid}: no ISO {iso} input (the noisy task needs ISO "
                f"{' and '.join(map(str, isos))}; it has {have})"
            )
    frames = rec.get("frames")
    return RealScene(sid, clean, target, noisy, dict(frames) if isinstance(frames, dict) else {},
                     outputs)


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def verify_outputs(scene, manifest):
    """Every output's size and SHA-256 equal the manifest's record of them."""
    for path, size, sha in scene.outputs:
        if not isinstance(sha, str) or not isinstance(size, int) or isinstance(size, bool):
            raise RealSetError(f"{manifest}: scene {scene.id}: {path.name} has no bytes and "
                               f"sha256 to check it against; {REMAKE}")
        try:
            got_size = path.stat().st_size
            got = sha256_file(path) if got_size == size else None
        except OSError as e:
            raise RealSetError(f"{path}: cannot read ({e.strerror or e}) (scene {scene.id})") \
                from None
        if got_size != size or got != sha.lower():
            what = (f"{got_size} bytes, the manifest records {size}" if got_size != size else
                    f"SHA-256 {got[:12]}..., the manifest records {sha[:12]}...")
            raise RealSetError(
                f"{path}: {what} (scene {scene.id}): the file or {manifest.name} changed after "
                f"real-pairs wrote them; {REMAKE}")


def raw_problem(raw):
    """Why a raw read from a DNG cannot be a network input (a string), or None."""
    if raw.data.ndim != 2 or raw.meta.get("cfa_pattern") is None:
        return "not a Bayer CFA mosaic (a LinearRaw or other non-CFA DNG)"
    if raw.meta.get("as_shot_neutral") is None:
        return "no AsShotNeutral (the white balance of the network input)"
    return None


def _read_dng(path, sid):
    try:
        raw = day2night.read_dng(str(path))
    except (OSError, ValueError) as e:
        raise RealSetError(f"{path}: cannot read the DNG (scene {sid}): {e}") from None
    why = raw_problem(raw)
    if why:
        raise RealSetError(f"{path}: {why} (scene {sid})")
    return raw


def check_scene(scene, manifest, clean=True, isos=()):
    """Check the files of ``scene`` the experiment reads, before it writes anything: sizes and
    SHA-256 (:func:`verify_outputs`), the clean raw (``clean``) and the noisy raws of
    ``isos`` as DNGs, the target as a PNG of the network input's size once cut and turned."""
    verify_outputs(scene, manifest)
    raws = ([scene.clean_raw] if clean else []) + [scene.noisy[i] for i in isos]
    try:
        h, w = check_png(scene.target)
    except PngError as e:
        raise RealSetError(f"{e} (the target of scene {scene.id}); {REMAKE}") from None
    target = np.broadcast_to(np.zeros(1, np.uint8), (h, w, 3))
    for path in raws:
        raw = _read_dng(path, scene.id)
        area = raw.meta.get("active_area") or [0, 0, *raw.data.shape[:2]]
        x = np.broadcast_to(np.zeros(1, np.uint8), (area[2] - area[0], area[3] - area[1], 3))
        if pairs.align(x, target, raw.meta) is None:
            raise RealSetError(
                f"{scene.target}: the target of scene {scene.id} is {w}x{h}; the network input "
                f"of {path.name} is {x.shape[1]}x{x.shape[0]} (active area), and neither its "
                f"DefaultCrop + Orientation nor a quarter turn matches it; {REMAKE}")
