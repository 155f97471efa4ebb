"""The one place day2night.train imports torch: a clear error when it is missing."""

try:
    import torch  # noqa: F401
except ImportError as e:  # pragma: no cover - exercised by test_train_import
    raise ImportError(
        "day2night.train's network, data sets, trainer and inference need PyTorch: "
        "pip install day2night[train]  (or pip install torch>=2.1); "
        f"importing torch failed: {e}"
    ) from e

__all__ = ["torch"]
