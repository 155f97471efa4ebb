"""The real night pairs written by ``day2night real-pairs SCENES -o OUT`` (docs/experiment.md):

    OUT/manifest.jsonl                    one JSON record per scene ("kind": "real", "scene")
    OUT/real/clean_raw/<id>.dng           merged clean raw (the first low-ISO frame's metadata)
    OUT/real/noisy_raw/<id>_iso<ISO>.dng  first frame of each high-ISO burst
    OUT/real/target/<id>.png              8-bit sRGB target
    OUT/real/meta/<id>.json               per-scene record

Records are read from the manifest's ``outputs`` (kind + path); every file named there must
exist. A failed record, a missing file or a scene without an ISO the task needs is an error
naming the scene and the file."""

import dataclasses
import json
import pathlib
import re

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
        clean = target = None
        noisy = {}
        for o in rec.get("outputs", []):
            path = root / o["path"]
            if not path.is_file():
                raise RealSetError(f"scene {sid}: {path} is listed in the manifest but missing")
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
        scenes[sid] = RealScene(sid, clean, target, noisy, dict(rec.get("frames") or {}))
    if not scenes:
        raise RealSetError(f"{manifest}: no real scene in the manifest")
    return [scenes[k] for k in sorted(scenes)]
