# test_gil.py - the GIL is released while the library computes: another Python thread runs in
# the middle of a long call (with the GIL held it could not run at all until the call returns).
import threading
import time

import numpy as np

import fluidsurf


def test_another_thread_runs_during_a_long_call():
    p = fluidsurf.generate("block", count=200000, radius=0.01)["positions"]
    ticks, stop = [], threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.001)

    worker = threading.Thread(target=count)
    worker.start()
    time.sleep(0.05)
    start = time.monotonic()
    mesh = fluidsurf.reconstruct(p, 0.01, threads=1)
    end = time.monotonic()
    stop.set()
    worker.join()
    assert len(mesh.triangles) > 0
    duration = end - start
    inside = [t for t in ticks if start + 0.1 * duration < t < end - 0.1 * duration]
    # ~1 ms per tick: a free thread ticks hundreds of times in the middle 80% of a 1 s call
    assert len(inside) > 10, (len(inside), duration)
