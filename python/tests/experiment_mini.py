"""A miniature version of the paper's data for the experiment's tests, made from the fixture
``fixtures/day.dng`` (a 512 x 512 active area):

- day images: 128 x 128 tiles of the fixture (each a DNG with a 2-pixel DefaultCrop margin);
- "real" night captures: tripod night bursts (``day2night synth --burst N --motion none`` at
  ISO 50, 1600 and 3200) of other tiles, which the training set never sees, written in the
  authors' burst layout (``<scene>/RAW_0_00<ISO:04>_<k>.dng``) and in the simple one (a folder
  per scene, ISO read from the DNGs).
"""

import pathlib
import shutil
import subprocess

import numpy as np

TILE = 128
# (row, col) tile indices of the 4 x 4 grid: training day images and real scenes differ
DAY_TILES = [(0, 0), (0, 2), (1, 1), (2, 3)]
SCENE_TILES = [(0, 1), (1, 0), (1, 3), (2, 0), (3, 1), (3, 3)]


def write_tile(day, r, c, path):
    """The (r, c) 128 x 128 tile of ``day``'s active area as a DNG."""
    import day2night

    top0, left0 = day.meta["active_area"][:2]
    top, left = top0 + r * TILE, left0 + c * TILE
    data = np.ascontiguousarray(day.data[top : top + TILE, left : left + TILE])
    meta = {k: v for k, v in day.meta.items() if v is not None}
    meta.update(active_area=None, default_crop=[2, 2, TILE - 4, TILE - 4], width=TILE,
                height=TILE)
    # tile offsets are even, so the CFA phase relative to the active area is unchanged
    raw = day2night.Raw.from_array(data, meta, name=path.stem)
    day2night.write_dng(raw, str(path), overwrite=True)


def day_dir(root, day_dng):
    import day2night

    day = day2night.read_dng(str(day_dng))
    out = pathlib.Path(root)
    out.mkdir(parents=True, exist_ok=True)
    for r, c in DAY_TILES:
        write_tile(day, r, c, out / f"day_{r}{c}.dng")
    return out


def bursts(cli, root, day_dng, frames=3, seed=5):
    """Night bursts of the scene tiles in both layouts: (release_dir, simple_dir)."""
    import day2night

    day = day2night.read_dng(str(day_dng))
    root = pathlib.Path(root)
    tiles, synth = root / "tiles", root / "synth"
    release, simple = root / "release", root / "simple"
    for d in (tiles, synth, release, simple):
        d.mkdir(parents=True, exist_ok=True)
    for i, (r, c) in enumerate(SCENE_TILES):
        scene = f"scene{i:02d}"
        tile = tiles / f"{scene}.dng"
        write_tile(day, r, c, tile)
        out = synth / scene
        cli("synth", tile, "-o", out, "--burst", frames, "--motion", "none",
            "--iso", "50,1600,3200", "--target", "none", "--seed", seed, "-q")
        (release / scene).mkdir(exist_ok=True)
        (simple / scene).mkdir(exist_ok=True)
        for iso in (50, 1600, 3200):
            for k in range(frames):
                src = out / f"{scene}_iso{iso}_f{k:02d}.dng"
                shutil.copy(src, release / scene / f"RAW_0_00{iso:04d}_{k:04d}.dng")
                shutil.copy(src, simple / scene / f"frame_{iso}_{k}.dng")
    return release, simple


def run_experiment(out, day, real, *extra, env=None, check=True):
    """``python -m day2night.experiment`` in a subprocess (the command users run)."""
    import sys

    cmd = [sys.executable, "-m", "day2night.experiment", "--day", str(day), "--real", str(real),
           "-o", str(out), *map(str, extra)]
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if check and r.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
    return r


def main(argv=None):
    """``python python/tests/experiment_mini.py OUT``: the miniature day images (OUT/days) and
    night bursts (OUT/captures/release, OUT/captures/simple) of the tests, for a smoke run."""
    import argparse

    p = argparse.ArgumentParser(description=main.__doc__)
    p.add_argument("out")
    p.add_argument("--day-dng", default=str(pathlib.Path(__file__).parents[2] / "fixtures" / "day.dng"))
    p.add_argument("--cli", default="day2night", help="the day2night binary")
    a = p.parse_args(argv)

    def cli(*args):
        subprocess.run([a.cli, *map(str, args)], check=True)

    out = pathlib.Path(a.out)
    day_dir(out / "days", a.day_dng)
    bursts(cli, out / "captures", a.day_dng)


if __name__ == "__main__":
    main()
