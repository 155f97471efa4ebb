"""The supplementary's burst-denoising row (noisy task; docs/experiment.md, "The burst row"):
no network, no training. For each real scene and noisy ISO the whole high-ISO burst of the
captures ``real-pairs`` made the real set from is averaged (``day2night.merge``: exactly as
real-pairs merges the ISO 50 burst), rendered by the run's target ISP, cut and turned onto
the test target's pixel grid as the pairing does (pairs.py), and scored like every row
(``train.scores.score``). No torch here.

The real set records, per scene (``real/meta/<id>.json``), its layout, its folder relative
to the captures (``input``) and the first frame of each ISO burst (name and SHA-256); the
manifest counts the frames per ISO. The frames themselves are in the captures folder
(``--captures SCENES``, the folder given to real-pairs). The row is left out, with the
reason, when the real set holds one frame per ISO (the authors' processed tree) or the
captures are not given; a captures folder that does not hold the bursts the real set
was made from is an error naming the file."""

import json
import pathlib

import numpy as np

import day2night

from ..isos import NOISY_ISOS
from ..atomic import write_json
from . import names, pairs
from . import rows as rows_mod
from ..train.scores import score
from ..train.targets import render_target
from .realset import sha256_file
from .unit import _num, _report_images
from .config import ExperimentError
from ..variants import Isp, Layout

ROW = "burst"
TASK = "noisy"


#: Why the burst row is left out of a run without --captures.
NO_CAPTURES = ("the captures the real set was made from are not given (--captures SCENES, the "
               "folder given to `day2night real-pairs`): the burst row averages their ISO "
               + " and ".join(map(str, NOISY_ISOS)) + " bursts")


def burst_rows(config, inputs, run_rows=None):
    """``(rows, left_out)``: the rows of the run (``run_rows``, default every row of
    ``config.rows``) with the burst row dropped when the real set cannot give it, and the
    ``[{"task", "row", "why"}]`` of what was dropped. ``inputs``: prepare.Inputs. When the
    row stays and its unit is not done, every scene's bursts are found and checked against
    the real set here (a mismatch is an ExperimentError)."""
    run_rows = list(run_rows if run_rows is not None else rows_mod.select(list(config.rows)))
    if TASK not in rows_mod.tasks_of(config.task):
        return run_rows, []
    if ROW not in [r.id for r in run_rows]:
        # not run: without --captures config.resolve leaves it out of the default rows
        return run_rows, [] if config.captures else [{"task": TASK, "row": ROW,
                                                       "why": unavailable(config, inputs)}]
    why = unavailable(config, inputs)
    if why:
        return [r for r in run_rows if r.id != ROW], [{"task": TASK, "row": ROW, "why": why}]
    if not (unit_dir(config.output) / "scores.json").is_file():
        frames(config, inputs)  # checked now, before anything is written
    return run_rows, []


def unit_dir(out):
    """The burst row's unit folder in the run folder ``out``."""
    return pathlib.Path(out) / "units" / TASK / ROW / "all"


def read_left_out(out):
    """The ``[{"task", "row", "why"}]`` of RUN/left_out.json (the runner writes it on every
    run; [] when absent: a run folder of an earlier version)."""
    path = pathlib.Path(out) / "left_out.json"
    if not path.is_file():
        return []
    try:
        got = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        raise ExperimentError(f"{path}: cannot read it ({e}); delete it and rerun") from None
    if not isinstance(got, list) or not all(
            isinstance(g, dict) and {"task", "row", "why"} <= set(g) for g in got):
        raise ExperimentError(f"{path}: not a list of {{task, row, why}}; delete it and rerun")
    return got


def unavailable(config, inputs):
    """Why the real set cannot give the burst row (a line), or None."""
    for sid in sorted(inputs.scenes):
        counts = inputs.scenes[sid].frames
        for iso in NOISY_ISOS:
            n = counts.get(str(iso))
            if not isinstance(n, int) or n < 2:
                return (f"the real set holds {n if isinstance(n, int) else 'no count of'} "
                        f"frame(s) at ISO {iso} for scene {sid} (the authors' processed tree "
                        "holds one per ISO): the burst row averages whole bursts")
    if not getattr(config, "captures", None):
        return NO_CAPTURES
    return None


def scene_record(scene):
    """The scene's ``real/meta/<id>.json`` (listed among its outputs), as a dict."""
    for path, _, _ in scene.outputs:
        if path.parent.name == "meta" and path.suffix == ".json":
            try:
                rec = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, ValueError) as e:
                raise ExperimentError(f"{path}: cannot read the scene record ({e})") from None
            if isinstance(rec, dict):
                return path, rec
            raise ExperimentError(f"{path}: the scene record is not a JSON object")
    raise ExperimentError(f"scene {scene.id}: the real set lists no real/meta/{scene.id}.json "
                          "(the scene record naming its frames)")


def _is_dng(p):
    return p.is_file() and p.suffix.lower() == ".dng" and not p.name.startswith(".")


def _iso_of(path, layout):
    """A frame's ISO as real-pairs reads it: from the release's name, else the DNG's Exif."""
    if layout == Layout.RELEASE:
        name = path.name
        if not name.startswith("RAW_0_00"):
            return None
        digits = ""
        for ch in name[len("RAW_0_00"):]:
            if not ch.isdigit():
                break
            digits += ch
        return int(digits[:4]) if len(digits) >= 4 else None
    try:
        iso = day2night.read_dng(str(path)).meta.get("iso")
    except (OSError, ValueError) as e:
        raise ExperimentError(f"{path}: cannot read the frame's ISO ({e})") from None
    return int(iso) if iso is not None else None


def scene_bursts(captures, scene, counts):
    """{ISO: [frame paths, sorted by name]} of a scene's high-ISO bursts in ``captures``,
    checked against the real set: as many frames as its manifest counts, the first one the
    noisy input its scene record names (same name and SHA-256)."""
    rpath, rec = scene_record(scene)
    layout, rel = rec.get("layout"), rec.get("input")
    folder = pathlib.Path(captures) / str(rel)
    if layout not in tuple(Layout) or not isinstance(rel, str) or not folder.is_dir():
        raise ExperimentError(
            f"--captures {captures}: no folder {rel!r} of scene {scene.id} (its record {rpath} "
            f"names layout {layout!r}): give the folder real-pairs made the real set from")
    files = sorted((p for p in folder.iterdir() if _is_dng(p)), key=lambda p: p.name.encode())
    out = {}
    for iso in NOISY_ISOS:
        burst = [p for p in files if _iso_of(p, layout) == iso]
        first = [f for f in rec.get("frames", []) if f.get("role") == "noisy"
                 and f.get("iso") == iso]
        want = counts.get(str(iso))
        problem = None
        if len(burst) != want:
            problem = f"{len(burst)} ISO {iso} frame(s), the real set's manifest counts {want}"
        elif not first or pathlib.PurePosixPath(first[0].get("name", "")).name != burst[0].name:
            problem = f"its first ISO {iso} frame {burst[0].name} is not the scene's noisy input"
        elif sha256_file(burst[0]) != first[0].get("sha256"):
            problem = f"{burst[0].name} is not the file real-pairs read (SHA-256 differs)"
        if problem:
            raise ExperimentError(f"--captures {captures}: scene {scene.id} ({folder}): "
                                  f"{problem}; give the folder real-pairs made the real set from")
        out[iso] = burst
    return out


def frames(config, inputs):
    """{scene: {ISO: [frame paths]}} of every real scene (:func:`scene_bursts`)."""
    return {sid: scene_bursts(config.captures, inputs.scenes[sid], inputs.scenes[sid].frames)
            for sid in sorted(inputs.scenes)}


def _release_grid(merged):
    """The release ISP's render of ``merged`` on the network input's grid (the active area,
    stored orientation): its window (``release_window``) in place, and the area it leaves
    out (none on the S20 FE and the fixtures) as None (the second value: the window)."""
    area = merged.meta.get("active_area") or [0, 0, *merged.data.shape[:2]]
    shape = (int(area[2]) - int(area[0]), int(area[3]) - int(area[1]))
    t, l, h, w = pairs.release_window(merged.meta, *shape)
    stored = np.asarray(render_target(merged, isp=Isp.RELEASE, orient=False), np.uint8)
    if stored.shape[:2] != (h, w):
        raise ExperimentError(f"{merged.file_name}: the release render is "
                              f"{stored.shape[1]}x{stored.shape[0]}, its window {w}x{h}")
    canvas = np.zeros((*shape, 3), np.uint8)
    canvas[t : t + h, l : l + w] = stored
    return canvas, (h, w)


def prediction(merged, y, geometry, targets):
    """The burst mean ``merged`` (a Raw) rendered by the run's ``targets`` ISP with its own
    AsShotNeutral, DNG opcode lists ignored (as every target), then cut and turned onto the
    pixel grid of the test target ``y`` (``geometry``: pairs.real_target's) exactly as the
    pairing cuts and turns a network input (pairs.align): ``(pred, y)``."""
    if targets == Isp.RELEASE:
        grid, window = _release_grid(merged)
    else:
        grid, _ = pairs.render_target_as(targets, merged, None, display=False)
        window = grid.shape[:2]
    got = pairs.align(grid, y, merged.meta, geometry)
    if got is None or (window != grid.shape[:2] and got[0].shape[:2] == grid.shape[:2]):
        raise ExperimentError(f"{merged.file_name}: the burst mean's {targets} render does "
                              f"not cover the target's pixel grid ({y.shape[1]}x{y.shape[0]})")
    return got


def score_scene(bursts, target, targets):
    """The per-input scores of one scene: ``bursts`` {ISO: frames}, ``target`` the scene's
    (uint8 target, geometry) (pairs.real_target). Yields ``(iso, record, pred, y)``."""
    y_raw, geometry = target
    for iso in NOISY_ISOS:
        try:
            merged, _ = day2night.merge([str(p) for p in bursts[iso]])
        except (OSError, ValueError) as e:
            raise ExperimentError(f"the ISO {iso} burst: {e}") from None
        pred, y = prediction(merged, np.asarray(y_raw), geometry, targets)
        s = score(pred, y)
        rec = {"input": str(iso), **{k: _num(s[k]) for k in ("psnr", "ssim", "delta_e")}}
        yield iso, rec, pred, y


def run_unit(out, config, inputs, target_isps, source=None, report_scenes=(), log=print):
    """Write RUN/units/noisy/burst/all/scores.json (skipped when it exists): every real
    scene x noisy ISO scored, in the format of the trained units' scores (``seed`` null, no
    history). ``target_isps``: {scene: ISP of its real target} (protocol.real_target_isps);
    ``source`` (a PairSource): the network inputs of ``report_scenes``, whose images go under
    RUN/img/noisy/burst as the trained rows' do."""
    udir = unit_dir(out)
    if (udir / "scores.json").is_file():
        log("done (scores.json), skipped")
        return
    test = sorted(inputs.scenes)
    found = frames(config, inputs)
    images = []
    for sid in test:
        log(f"scene {sid}: averaging the " + " and ".join(
            f"{len(found[sid][i])} ISO {i}" for i in NOISY_ISOS) + " frames")
        try:
            target = pairs.real_target(inputs.scenes[sid], config.targets,
                                       target_isps.get(sid, "day2night"))
        except (pairs.PairError, ValueError) as e:
            raise ExperimentError(str(e)) from None
        for iso, rec, pred, y in score_scene(found[sid], target, config.targets):
            images.append({"scene": sid, **rec})
            if source is not None and sid in report_scenes:
                x = pairs.load(source.real(sid, iso)[0])
                _report_images(pathlib.Path(out) / "img" / TASK, ROW,
                               names.image_stem(sid, iso), x, y, pred)
    write_json(udir / "scores.json", {
        "task": TASK, "row": ROW, "fold": "all", "seed": None, "history": [], "initial": {},
        "images": images, "train_pairs": 0, "val_pairs": 0, "test_scenes": test,
        "frames": {sid: {str(i): len(found[sid][i]) for i in NOISY_ISOS} for sid in test},
    })
