"""The paper's experiment (Tables 1 and 2): a night ISP trained on day2night's synthetic pairs,
on a mix with real pairs, or on real pairs alone (k-fold), scored on real night captures.

    python -m day2night.experiment --day DAY_DIR --real REAL_DIR -o RUN/

``folds`` (k-fold manifests) and ``mix`` (x % real training slots) need numpy only; training
imports torch (the package's ``train`` extra; from a checkout ``scripts/dev-install.sh``). See docs/experiment.md of the repository."""

from .folds import FoldError, make_folds, read_folds, write_folds  # noqa: F401
from .mix import MixError, real_count  # noqa: F401
