"""The GIL is released during computations: another Python thread runs meanwhile.

Shown without a clock (issue 36): ``synthesize`` reads its noise model inside the section
where it has released the GIL, and here that file is a FIFO which only the test's own
Python thread writes. The test thread's ``open`` for writing returns once the computation
has opened the FIFO to read; writing it then needs the GIL. Were the GIL held during the
computation, the writer could not run and the call could never return; released, the
computation reads the model and completes. (How much two Python threads gain is measured,
not tested: benches/python_pairs.py.)"""

import os
import pathlib
import threading
import warnings

import day2night

NOISE_MODEL = (pathlib.Path(__file__).resolve().parents[2] / "calibration" / "samsung-s20fe"
               / "noise.json")


def test_other_threads_run_during_a_computation(day_dng, tmp_path):
    raw = day2night.read_dng(day_dng)
    gate = tmp_path / "noise.json"
    os.mkfifo(gate)
    result = {}

    def compute():
        try:
            with warnings.catch_warnings():
                # the model is another camera's: said, and beside the point here
                warnings.simplefilter("ignore", day2night.diagnostics.NoiseOtherCameraWarning)
                result["night"] = day2night.synthesize(raw, isos=(1600,), noise_model=str(gate))
        except BaseException as e:  # noqa: BLE001 (reported by the test thread)
            result["error"] = e

    worker = threading.Thread(target=compute, daemon=True)
    worker.start()
    # Returns once the computation opened the FIFO (it is then inside synthesize); this
    # thread then runs Python while the computation waits for the bytes.
    with open(gate, "wb") as f:
        f.write(NOISE_MODEL.read_bytes())
    worker.join()
    assert "error" not in result, result.get("error")
    night = result["night"]
    assert str(gate) in str(night["noise_provenance"]), night["noise_provenance"]
    assert night["noisy"][1600].shape[:2] == night["clean"].shape[:2]
