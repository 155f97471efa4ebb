"""The experiment's remaining tracebacks as one line (issue 42 item 8): a killed DataLoader
worker (exit 1, saying that the same command resumes the run), an error raised inside a
worker (its own message, not torch's wrapper and the worker's traceback)."""

import os
import signal

import pytest

from day2night.experiment import __main__ as cli
from day2night.experiment import runner


def run_main(tmp_path, monkeypatch, capsys, fail):
    monkeypatch.setattr(runner.Experiment, "run", lambda self: fail())
    code = cli.main(["--day", str(tmp_path), "--real", str(tmp_path), "-o",
                     str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return code, err


class _Dies:
    """A dataset whose worker process kills itself (SIGKILL) on its first item."""

    def __len__(self):
        return 4

    def __getitem__(self, i):
        os.kill(os.getpid(), signal.SIGKILL)


class _Raises:
    def __len__(self):
        return 4

    def __getitem__(self, i):
        raise ValueError("RUN/data/real/000.in.npy: code 20000 past the 16384-entry table")


def _iterate(dataset):
    torch = pytest.importorskip("torch")
    for _ in torch.utils.data.DataLoader(dataset, num_workers=1):
        pass


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL")
def test_a_killed_worker_is_one_line_exit_1_and_says_resume(tmp_path, monkeypatch, capsys):
    pytest.importorskip("torch")
    code, err = run_main(tmp_path, monkeypatch, capsys, lambda: _iterate(_Dies()))
    assert code == 1
    assert err.startswith("day2night.experiment: error: a DataLoader worker died: ")
    assert err.rstrip().endswith("rerun the same command to resume")


def test_an_error_inside_a_worker_is_its_own_line(tmp_path, monkeypatch, capsys):
    pytest.importorskip("torch")
    code, err = run_main(tmp_path, monkeypatch, capsys, lambda: _iterate(_Raises()))
    assert code == 2
    assert "RUN/data/real/000.in.npy: code 20000 past the 16384-entry table" in err
    assert "Traceback" not in err and "DataLoader worker process" not in err


def test_one_line_of_each_kind():
    wrapped = ValueError("Caught ValueError in DataLoader worker process 0.\nOriginal "
                         "Traceback (most recent call last):\n  File \"x.py\", line 1\n"
                         "ValueError: the worker's message\n")
    assert cli.one_line(wrapped) == "ValueError: the worker's message"
    assert cli.one_line(ValueError("first\nsecond")) == "first"
    assert cli.one_line(RuntimeError("")) == "RuntimeError"
