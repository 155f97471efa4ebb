"""``day2night.merge``'s paths (issue 47): ``str``, ``bytes`` and ``os.PathLike`` are taken,
as its TypeError for anything else says, and the same file given twice (by the same path,
through ``./`` or a link) is refused with a ValueError naming it, not averaged double."""

import os
import pathlib

import numpy as np
import pytest

import day2night

from conftest import FIXTURES


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    out = tmp_path_factory.mktemp("burst")
    raw = day2night.read_dng(str(FIXTURES / "day.dng"))
    tripod = day2night.synthesize(raw, seed=0, isos=(1600,), burst=3, motion="none")
    day2night.write_outputs(tripod, raw, str(out))
    paths = sorted(out.glob("day_iso1600_f*.dng"))
    assert len(paths) == 3
    return paths


def test_str_bytes_and_pathlike_give_the_same_merge(frames):
    ref, report = day2night.merge([str(p) for p in frames])
    assert report["frames"] == 3
    for paths in ([os.fsencode(p) for p in frames], list(frames),
                  [str(frames[0]), os.fsencode(frames[1]), frames[2]]):
        got, rep = day2night.merge(paths)
        assert np.array_equal(np.asarray(got.data), np.asarray(ref.data))
        assert rep == report and got.name == ref.name


def test_other_types_are_the_type_error_it_names(frames):
    with pytest.raises(TypeError, match="str, bytes or os.PathLike"):
        day2night.merge([str(frames[0]), None])
    with pytest.raises(TypeError, match="str, bytes or os.PathLike"):
        day2night.merge([str(frames[0]), 3])
    with pytest.raises(TypeError):
        day2night.merge(str(frames[0]))  # a string is not a list of paths


def test_the_same_frame_twice_is_refused(frames, tmp_path):
    a, b = str(frames[0]), str(frames[1])
    with pytest.raises(ValueError, match=r"merge got this frame twice \(paths 0 and 2 of 3\)"):
        day2night.merge([a, b, a])
    # the same file through another spelling of its path, or a link to it
    other = os.path.join(os.path.dirname(a), ".", os.path.basename(a))
    with pytest.raises(ValueError, match="twice"):
        day2night.merge([a, b, other])
    link = tmp_path / "link.dng"
    link.symlink_to(frames[1])
    with pytest.raises(ValueError, match=f"{link}: merge got this frame twice"):
        day2night.merge([a, b, link])
    # a copy is another file: merged (two frames with the same samples)
    copy = tmp_path / "copy.dng"
    copy.write_bytes(pathlib.Path(a).read_bytes())
    _, report = day2night.merge([a, copy])
    assert report["frames"] == 2
