"""The one place day2night imports torch (the optional ``train`` extra:
``pip install day2night[train]``).

``torch`` is the module where it is installed. Where it is not, ``torch`` is a stand-in whose
every attribute raises the ImportError that says how to install it, and ``Module`` and
``Dataset`` (torch's base classes of a network and of a data set) are a stand-in that raises it
when instantiated. A damaged install (``import torch`` raising OSError because a shared
library is missing) counts as not installed, with that error in the message. So every module
imports what it needs at its top, with or without torch
(``python -m day2night.train --help`` and ``python -m day2night.experiment --help`` need none),
and a missing torch is reported where it is first needed. ``import day2night``,
``import day2night.train`` and its numpy modules (``preprocess``, ``targets``, ``scores``,
``cache``) never import this module."""

import functools

try:
    import torch
except (ImportError, OSError) as e:  # exercised by test_train_import
    # OSError: an install with a shared library missing (a pip install cut short leaves
    # one); reported like a missing torch, so what needs no torch still runs
    torch = None
    _FAILED = f"{type(e).__name__}: {e}"
else:
    _FAILED = None


def missing():
    """The ImportError a use of torch raises where it is not installed."""
    return ImportError(
        "day2night.train's network, data sets, trainer and inference need PyTorch: "
        "pip install day2night[train]  (or pip install torch>=2.1); "
        f"importing torch failed: {_FAILED}"
    )


class _Missing:
    """torch where it is not installed: any attribute raises :func:`missing`."""

    def __getattr__(self, name):
        raise missing()


class _NeedsTorch:
    """``Module`` and ``Dataset`` where torch is not installed: instances cannot be made."""

    def __new__(cls, *args, **kwargs):
        raise missing()


if torch is None:
    torch = _Missing()
    Module = Dataset = _NeedsTorch
else:
    Module, Dataset = torch.nn.Module, torch.utils.data.Dataset


def available():
    """Whether torch could be imported."""
    return _FAILED is None


def no_grad(f):
    """``f`` run under ``torch.no_grad()`` (resolved when it runs, not when it is defined)."""

    @functools.wraps(f)
    def run(*args, **kwargs):
        with torch.no_grad():
            return f(*args, **kwargs)

    return run


__all__ = ["torch", "Module", "Dataset", "available", "missing", "no_grad"]
