"""benches/train_gpu.py runs tiny on a CPU (issue 35 item 6): the GPU benchmark's code path
(training steps with the options, 12 MP inference replaced by a small image) works, with and
without bf16 and channels-last, and prints its numbers as JSON."""

import json
import os
import subprocess
import sys

import pytest

from conftest import ROOT, need_torch


@pytest.mark.parametrize("extra", [[], ["--amp", "bf16", "--channels-last"]])
def test_train_gpu_bench_runs_tiny_on_cpu(extra):
    need_torch()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    r = subprocess.run([sys.executable, str(ROOT / "benches" / "train_gpu.py"), "--tiny",
                        "--device", "cpu", *extra], capture_output=True, text=True, env=env,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout.strip().splitlines()[-1])
    assert res["device"] == "cpu" and res["width"] == 4 and res["batch"] == 4
    assert res["train"]["steps_per_s"] > 0 and res["train"]["peak_bytes"] > 0
    assert res["infer"]["size"] == [96, 64] and res["infer"]["seconds"] > 0
    assert res["amp"] == (extra[1] if extra else None)
    assert "steps/s" in r.stdout and "inference 96x64" in r.stdout
