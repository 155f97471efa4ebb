"""The experiment's remaining tracebacks as one line (issue 42 item 8): a killed DataLoader
worker (exit 1, saying that the same command resumes the run), an error raised inside a
worker (its own message, not torch's wrapper and the worker's traceback)."""

import os
import signal

import pytest

from conftest import need_torch
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
    torch = need_torch()
    for _ in torch.utils.data.DataLoader(dataset, num_workers=1):
        pass


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL")
def test_a_killed_worker_is_one_line_exit_1_and_says_resume(tmp_path, monkeypatch, capsys):
    need_torch()
    code, err = run_main(tmp_path, monkeypatch, capsys, lambda: _iterate(_Dies()))
    assert code == 1
    assert err.startswith("day2night.experiment: error: a DataLoader worker died: ")
    assert err.rstrip().endswith("rerun the same command to resume")


def test_an_error_inside_a_worker_is_its_own_line(tmp_path, monkeypatch, capsys):
    need_torch()
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


def _main_with(tmp_path, monkeypatch, capsys, run):
    monkeypatch.setattr(runner.Experiment, "run", run)
    code = cli.main(["--day", str(tmp_path), "--real", str(tmp_path), "-o",
                     str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return code, err


def _raise(e, unit=None):
    def run(self):
        self.current_unit = unit
        raise e
    return run


def test_a_bug_is_named_with_its_unit_and_not_called_resumable(tmp_path, monkeypatch, capsys):
    unit = "unit 3/28: task clean, row ours (Ours), fold all"
    code, err = _main_with(tmp_path, monkeypatch, capsys,
                           _raise(RuntimeError("mat1 and mat2 shapes cannot be multiplied"),
                                  unit))
    assert code == 1
    assert err == (f"day2night.experiment: error: RuntimeError in {unit}: mat1 and mat2 shapes "
                   "cannot be multiplied (not an interruption: the same command stops here "
                   "again; RUN/log.txt holds the run's output)\n")
    assert "resume" not in err
    # an exception inside a worker (bad data) is no killed worker either
    wrapped = RuntimeError("Caught RuntimeError in DataLoader worker process 0.\nOriginal "
                           "Traceback (most recent call last):\nRuntimeError: bad sample\n")
    code, err = _main_with(tmp_path, monkeypatch, capsys, _raise(wrapped))
    assert code == 1 and "resume" not in err and "RuntimeError: bad sample" in err


@pytest.mark.parametrize("e", [MemoryError(), RuntimeError("CUDA out of memory. Tried to "
                                                           "allocate 2.00 GiB"),
                               RuntimeError("[enforce fail at alloc_cpu.cpp:117] "
                                            "DefaultCPUAllocator: can't allocate memory")])
def test_out_of_memory_says_resume(tmp_path, monkeypatch, capsys, e):
    code, err = _main_with(tmp_path, monkeypatch, capsys, _raise(e, "unit 1/2: task noisy"))
    assert code == 1
    assert err.startswith("day2night.experiment: error: out of memory in unit 1/2: task noisy")
    assert "rerun the same command to resume from its last complete epoch" in err


def test_sigterm_says_resume_and_the_handler_is_restored(tmp_path, monkeypatch, capsys):
    before = signal.getsignal(signal.SIGTERM)
    code, err = _main_with(tmp_path, monkeypatch, capsys,
                           lambda self: os.kill(os.getpid(), signal.SIGTERM))
    assert code == 128 + signal.SIGTERM
    assert err == ("day2night.experiment: terminated (SIGTERM): rerun the same command to "
                   "resume\n")
    assert signal.getsignal(signal.SIGTERM) is before
