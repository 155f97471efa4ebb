"""The documented way from a checkout (README.md, "Install"; issue 41): scripts/dev-install.sh
puts the wheel built here, with its train extra, into a virtualenv, so that `day2night` is on
PATH when the venv is active and `import day2night.train` works. scripts/test.sh installs its
own wheel with it into the venv these tests run in and says so (D2N_DEV_VENV), so the suite
runs on what the script installed."""

import os
import pathlib
import subprocess
import sys

import pytest

from conftest import ROOT

import day2night

SCRIPT = ROOT / "scripts" / "dev-install.sh"
VENV = os.environ.get("D2N_DEV_VENV")


@pytest.fixture
def venv():
    if not VENV:
        pytest.skip("D2N_DEV_VENV is not set: scripts/test.sh sets it after installing the "
                    "package with scripts/dev-install.sh")
    return pathlib.Path(VENV)


def test_the_tests_run_in_the_installed_venv(venv):
    assert pathlib.Path(sys.prefix).resolve() == venv.resolve()
    assert pathlib.Path(day2night.__file__).resolve().is_relative_to(venv.resolve())


def test_day2night_is_on_path_in_the_active_venv(venv):
    env = {"PATH": f"{venv / 'bin'}:/usr/bin:/bin", "HOME": os.environ.get("HOME", "/tmp"),
           "VIRTUAL_ENV": str(venv)}
    where = subprocess.run(["sh", "-c", "command -v day2night"], env=env, capture_output=True,
                           text=True, check=True).stdout.strip()
    assert where == str(venv / "bin" / "day2night")
    got = subprocess.run([where, "--version"], capture_output=True, text=True, check=True)
    assert got.stdout.strip() == f"day2night {day2night.__version__}"


def test_the_train_extra_is_installed(venv):
    if os.environ.get("D2N_DEV_TRAIN") != "1":
        pytest.skip("torch could not be installed: scripts/test.sh ran scripts/dev-install.sh "
                    "--no-train")
    r = subprocess.run([str(venv / "bin" / "python"), "-c",
                        "import day2night.train, torch; print(day2night.train.UNet.__name__)"],
                       capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.strip() == "UNet", r.stderr


def test_bad_usage_and_a_missing_wheel_are_clear_errors(tmp_path):
    r = subprocess.run(["bash", str(SCRIPT), "--bogus"], capture_output=True, text=True)
    assert r.returncode == 2 and "unknown option --bogus" in r.stderr
    r = subprocess.run(["bash", str(SCRIPT), str(tmp_path / "v"), "--no-train"],
                       capture_output=True, text=True,
                       env=dict(os.environ, D2N_WHEEL=str(tmp_path / "none.whl")))
    assert r.returncode == 1
    assert f"scripts/dev-install.sh: no wheel at {tmp_path / 'none.whl'} (D2N_WHEEL)" in r.stderr
    assert not (tmp_path / "v").exists()


def test_the_readme_documents_it():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "scripts/dev-install.sh" in readme
    assert "nothing is published on a package index yet" in readme.lower()


def _tool(path, body):
    path.write_text("#!/usr/bin/env bash\n" + body)
    path.chmod(0o755)


def test_the_binary_is_compiled_once(tmp_path):
    """scripts/dev-install.sh builds the binary README's main command builds (`cargo build
    --release`, into the target folder `cargo run --release` uses) and puts that one in the
    wheel (scripts/wheel.sh with D2N_WHEEL_BIN): cargo-zigbuild never runs. Run against
    stand-ins for cargo, maturin, cargo-zigbuild and the venv's python that log their
    calls (no compiler, no network)."""
    log, target, venv, fake = tmp_path / "log", tmp_path / "target", tmp_path / "venv", \
        tmp_path / "fake"
    (venv / "bin").mkdir(parents=True)
    fake.mkdir()
    version = day2night.__version__
    _tool(fake / "cargo", f'echo "cargo $*" >> {log}\nmkdir -p "$CARGO_TARGET_DIR/release"\n'
          f'printf "#!/bin/sh\\necho day2night {version}\\n" > '
          '"$CARGO_TARGET_DIR/release/day2night"\nchmod +x "$CARGO_TARGET_DIR/release/day2night"\n')
    _tool(venv / "bin" / "python", f'echo "python $*" >> {log}\n')
    _tool(venv / "bin" / "cargo-zigbuild", f'echo "cargo-zigbuild $*" >> {log}\n')
    _tool(venv / "bin" / "maturin", f'echo "maturin $*" >> {log}\n'
          'while [ $# -gt 0 ]; do [ "$1" = -o ] && out="$2"; shift; done\n'
          f'mkdir -p "$out" && touch "$out/day2night-{version}-cp39-abi3-manylinux_2_17_x86_64.whl"\n')
    _tool(venv / "bin" / "day2night", f"echo day2night {version}\n")
    env = dict(os.environ, PATH=f"{fake}:{os.environ['PATH']}", CARGO_TARGET_DIR=str(target))
    env.pop("D2N_WHEEL", None)
    r = subprocess.run(["bash", str(SCRIPT), str(venv), "--no-train"], capture_output=True,
                       text=True, env=env)
    assert r.returncode == 0, r.stderr
    calls = log.read_text().splitlines()
    assert [c for c in calls if c.startswith("cargo")] == [
        "cargo build --quiet --release --locked --bin day2night"]
    assert any(c.startswith("maturin build") for c in calls)
    add = [c for c in calls if "wheel_add_script.py" in c]
    assert len(add) == 1 and add[0].endswith(f" {target / 'release' / 'day2night'}")
    assert "D2N_WHEEL_BIN" in r.stderr and "this machine's" in r.stderr


def test_wheel_bin_must_be_an_executable(tmp_path):
    venv = tmp_path / "venv"
    (venv / "bin").mkdir(parents=True)
    for t in ("python", "maturin", "cargo-zigbuild"):
        _tool(venv / "bin" / t, "exit 0\n")
    r = subprocess.run(["bash", str(ROOT / "scripts" / "wheel.sh"), str(tmp_path / "w")],
                       capture_output=True, text=True,
                       env=dict(os.environ, D2N_WHEEL_PYTHON=str(venv / "bin" / "python"),
                                D2N_WHEEL_BIN=str(tmp_path / "none")))
    assert r.returncode == 1
    assert f"D2N_WHEEL_BIN={tmp_path / 'none'} is not an executable file" in r.stderr
