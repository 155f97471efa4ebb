"""The GIL is released during computations: another Python thread runs meanwhile. (How
much two Python threads gain is measured, not tested: benches/python_pairs.py.)"""

import threading
import time

import day2night


def test_other_threads_run_during_a_computation(real_dng):
    raw = day2night.read_dng(real_dng)
    day2night.synthesize(raw, isos=(1600,))  # warm up
    ticks = 0
    done = threading.Event()

    def count():
        nonlocal ticks
        while not done.is_set():
            ticks += 1

    t = threading.Thread(target=count)
    t.start()
    try:
        t0 = time.perf_counter()
        for _ in range(3):
            day2night.synthesize(raw, isos=(1600, 3200))
        elapsed = time.perf_counter() - t0
    finally:
        done.set()
        t.join()
    # With the GIL held for the whole computation the counter would barely move (it only
    # runs between calls); released, it runs for most of the elapsed time.
    assert elapsed > 0.05
    assert ticks > 20000, (ticks, elapsed)
