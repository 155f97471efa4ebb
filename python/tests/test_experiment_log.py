"""The experiment's log (issue 41, part 5; experiment/runlog.py): each warning kind printed
once with its count at the end, every warning and every line in RUN/log.txt, the trainer's
in-place step counter resolved to one line per epoch when stderr is not a terminal."""

import io
import os
import re
import sys
import warnings

import pytest

import day2night
from day2night.experiment import runlog


class Stream(io.StringIO):
    def __init__(self, tty=False):
        super().__init__()
        self.tty = tty

    def isatty(self):
        return self.tty


def use_stderr(monkeypatch, tty=False):
    """A stream in place of sys.stderr (set in the test itself: pytest's capture sets
    sys.stderr again when the test's call begins)."""
    s = Stream(tty)
    monkeypatch.setattr(sys, "stderr", s)
    return s


def lines(path):
    """The log file's lines without their time stamps."""
    text = path.read_text(encoding="utf-8")
    assert all(re.match(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ ", line) for line in text.splitlines())
    return [line[21:] for line in text.splitlines()]


def test_each_kind_once_with_its_count_and_every_one_in_the_file(monkeypatch, tmp_path):
    stderr = use_stderr(monkeypatch)
    with runlog.capture() as log:
        print("[experiment] checking", file=sys.stderr)  # before the file: held
        for i in range(22):
            warnings.warn(day2night.NoiseExtrapolatedWarning(f"extrapolated {i}"))
        log.open(tmp_path / "log.txt")
        warnings.warn("a plain one")
        warnings.warn(day2night.NoiseExtrapolatedWarning("extrapolated again"))
    out = stderr.getvalue().splitlines()
    assert out == [
        "[experiment] checking",
        "[experiment] warning NoiseExtrapolatedWarning: extrapolated 0 (the first of its "
        "kind; the count comes at the end of the run)",
        "[experiment] warning UserWarning: a plain one (the first of its kind; the count "
        "comes at the end of the run)",
        f"[experiment] warnings of this run: NoiseExtrapolatedWarning x23, UserWarning x1 "
        f"(every one in {tmp_path / 'log.txt'})",
    ]
    got = lines(tmp_path / "log.txt")
    assert got[0] == "[experiment] checking"
    warned = [x for x in got if x.startswith("warning ")]
    assert len(warned) == 24
    assert re.fullmatch(r"warning NoiseExtrapolatedWarning \(test_experiment_log.py:\d+\): "
                        r"extrapolated 21", warned[21])
    assert got[-1] == out[-1]
    assert sys.stderr is stderr  # restored


def test_a_redirected_log_has_one_line_per_epoch_and_a_terminal_the_rewrites(monkeypatch,
                                                                                tmp_path):
    for tty in (False, True):
        s = use_stderr(monkeypatch, tty)
        path = tmp_path / f"log{tty}.txt"
        with runlog.capture() as log:
            log.open(path)
            for step in (1, 2, 3):
                sys.stderr.write(f"\repoch 1/2  step {step}/3  loss 0.5   ")
            sys.stderr.write("\repoch 1/2  loss 0.4  val loss 0.3\n")
            print("[experiment] unit 1/1: scoring", file=sys.stderr)
        want = ["epoch 1/2  loss 0.4  val loss 0.3", "[experiment] unit 1/1: scoring"]
        assert lines(path) == want
        if tty:
            assert s.getvalue().startswith("\repoch 1/2  step 1/3")
        else:
            assert s.getvalue().splitlines() == want


def test_appended_by_a_resumed_run_and_no_file_before_the_run_folder(monkeypatch, tmp_path):
    stderr = use_stderr(monkeypatch)
    path = tmp_path / "log.txt"
    for run in ("first", "second"):
        with runlog.capture() as log:
            log.open(path)
            print(f"[experiment] {run}", file=sys.stderr)
    assert lines(path) == ["[experiment] first", "[experiment] second"]
    with pytest.raises(RuntimeError):
        with runlog.capture():
            warnings.warn("early")
            raise RuntimeError("a bad input, found before anything is written")
    assert stderr.getvalue().splitlines()[-1] == (
        "[experiment] warnings of this run: UserWarning x1 (not written to a log file: the "
        "run stopped before its run folder)")
    assert sorted(os.listdir(tmp_path)) == ["log.txt"]
