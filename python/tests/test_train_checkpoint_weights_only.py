"""Checkpoints are read with ``torch.load(..., weights_only=True)`` (issue 42 item 10): what the
trainer saves (model, Adam's state, MultiStepLR's state, config, history, best score) loads that
way and resumes the same schedule, and a checkpoint holding any other object is a one-line
CheckpointError naming the file, never unpickled."""

import collections
import os

import pytest

from conftest import need_torch

torch = need_torch(module=True)

from day2night.train import trainer  # noqa: E402


class _Payload:
    """An object a weights-only load refuses (its __reduce__ would run code when unpickled)."""

    def __reduce__(self):
        return (os.system, ("touch should-not-exist",))


def _parts():
    torch.manual_seed(0)
    model = torch.nn.Linear(3, 2)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    sched = torch.optim.lr_scheduler.MultiStepLR(opt, [2], 0.1)
    return model, opt, sched


def test_the_trainers_state_loads_weights_only_and_resumes_the_schedule(tmp_path):
    model, opt, sched = _parts()
    for _ in range(2):
        model(torch.ones(1, 3)).sum().backward()
        opt.step()
        sched.step()
    path = tmp_path / "last.pt"
    trainer.save_checkpoint(path, model=trainer._state(model), optimizer=opt.state_dict(),
                            scheduler=trainer.scheduler_state(sched),
                            config={"init_features": 4, "amp": None, "lr": 1e-3},
                            epoch=1, history=[{"epoch": 0, "loss": 0.5}],
                            best_val=float("inf"), initial=None)
    ck = trainer.load_checkpoint(str(path), keys=trainer.RESUME_STATE)
    model2, opt2, sched2 = _parts()
    model2.load_state_dict(ck["model"])
    opt2.load_state_dict(ck["optimizer"])
    trainer.load_scheduler(sched2, ck["scheduler"])
    assert isinstance(sched2.milestones, collections.Counter)
    assert sched2.get_last_lr() == sched.get_last_lr()
    sched.step()
    sched2.step()
    assert sched2.get_last_lr() == sched.get_last_lr()


def test_a_checkpoint_with_another_object_is_refused_naming_it(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "best.pt"
    torch.save({"model": {}, "config": {}, "epoch": 0, "extra": _Payload()}, path)
    with pytest.raises(trainer.CheckpointError, match=rf"{path}: a checkpoint holding objects "
                       "other than tensors and plain values is not loaded") as e:
        trainer.load_checkpoint(str(path))
    assert "\n" not in str(e.value)
    assert not (tmp_path / "should-not-exist").exists()
