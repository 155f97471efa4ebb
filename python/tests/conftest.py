"""Shared fixtures of the Python package's tests (run by scripts/test.sh after cargo test).

The command-line binary they compare against is D2N_BIN (scripts/test.sh sets it to the
debug build cargo test made), else target/debug/day2night of the checkout."""

import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"
SHARED_DATA = pathlib.Path(os.environ.get("D2N_SHARED_DATA") or ROOT.parent / "shared" / "data")
SHARED = SHARED_DATA / "dng"


def shared_file(rel):
    """A file of the shared real-camera data (../shared/data or $D2N_SHARED_DATA): the test
    skips with the reason when it is absent, or fails when D2N_REQUIRE_SHARED_DATA=1
    (.ci/run sets it when ../shared/data exists)."""
    p = SHARED_DATA / rel
    if p.is_file():
        return p
    missing(f"shared real-camera file {p} not found (set D2N_SHARED_DATA)")


def missing(why):
    if os.environ.get("D2N_REQUIRE_SHARED_DATA") == "1":
        pytest.fail(f"{why} but D2N_REQUIRE_SHARED_DATA=1")
    pytest.skip(why)


def require_tool(name, package):
    """The path of the system tool NAME. Absent, the test fails under D2N_REQUIRE_TOOLS=1
    (scripts/test.sh sets it unless D2N_REQUIRE_TOOLS=0) and is reported as skipped, with
    the reason, otherwise (never as passed)."""
    exe = shutil.which(name)
    if exe is not None:
        return exe
    why = f"{name} not installed (Debian {package}; .ci/run installs it)"
    if os.environ.get("D2N_REQUIRE_TOOLS") == "1":
        pytest.fail(f"{why} but D2N_REQUIRE_TOOLS=1")
    pytest.skip(why)


def cli_path():
    p = os.environ.get("D2N_BIN") or str(ROOT / "target" / "debug" / "day2night")
    if not os.access(p, os.X_OK):
        pytest.fail(f"day2night binary not found at {p}: run cargo build first or set D2N_BIN")
    return p


@pytest.fixture(scope="session")
def cli():
    path = cli_path()

    def run(*args, check=True):
        r = subprocess.run([path, *map(str, args)], capture_output=True, text=True)
        if check and r.returncode != 0:
            raise AssertionError(f"day2night {' '.join(map(str, args))} failed: {r.stderr}")
        return r

    return run


@pytest.fixture(scope="session")
def day_dng():
    return FIXTURES / "day.dng"


@pytest.fixture(scope="session")
def real_dng():
    files = sorted(SHARED.glob("*.dng")) if SHARED.is_dir() else []
    if not files:
        missing(f"no real DNG in {SHARED} (shared real-camera data; set D2N_SHARED_DATA)")
    return files[0]


@pytest.fixture()
def day_dir(tmp_path, day_dng):
    d = tmp_path / "days"
    d.mkdir()
    shutil.copy(day_dng, d / "a.dng")
    shutil.copy(day_dng, d / "b.dng")
    return d


_TORCH = []  # [(module or None, why not)], filled by the first need_torch()


def need_torch(module=False):
    """torch for the trainer's and the experiment's tests: imported, or the test (the whole
    module with ``module=True``, called at its top) skips with the reason scripts/test.sh
    gave, or fails when D2N_REQUIRE_TORCH=1 (set by scripts/test.sh once torch is installed).

    torch is imported once per pytest process: a damaged install (a shared library missing,
    as a pip install cut short leaves it) raises OSError the first time and ImportError
    ("can only be initialized once") after, so both are caught, and the first reason is the
    one every skip gives."""
    if not _TORCH:
        try:
            import torch
        except (ImportError, OSError) as e:
            _TORCH.append((None, f"{type(e).__name__}: {e}"))
        else:
            _TORCH.append((torch, None))
    torch, why = _TORCH[0]
    if torch is None:
        if os.environ.get("D2N_REQUIRE_TORCH") == "1":
            pytest.fail(f"D2N_REQUIRE_TORCH=1 but torch cannot be imported: {why}", pytrace=False)
        reason = os.environ.get("D2N_TORCH_SKIP_REASON") or f"torch cannot be imported ({why})"
        pytest.skip(reason, allow_module_level=module)
    return torch
