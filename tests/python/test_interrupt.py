# test_interrupt.py - Ctrl-C during a long call (issue 63): the KeyboardInterrupt came only when
# the call ended, 13 s late. Now the library is cancelled through its context and the call raises
# KeyboardInterrupt within a range of work; the process is not killed, and the next call works.
import os
import signal
import subprocess
import sys
import time

CHILD = r"""
import sys, time, fluidsurf
p = fluidsurf.generate("drop", count=1000000, radius=0.01)["positions"]
print("started", flush=True)
t = time.monotonic()
try:
    fluidsurf.reconstruct(p, 0.01, voxel=0.35)
    print("finished without an interrupt", flush=True)
except KeyboardInterrupt:
    print("interrupted after %.3f s" % (time.monotonic() - t), flush=True)
    m = fluidsurf.reconstruct(p[:2000], 0.01, raw=True)  # the library still works
    print("then %d triangles" % len(m.triangles), flush=True)
"""


def test_ctrl_c_interrupts_a_long_call_within_a_second():
    child = subprocess.Popen([sys.executable, "-c", CHILD], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, env=os.environ.copy())
    assert child.stdout.readline().strip() == "started"
    time.sleep(0.5)  # inside the call
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=60)
    waited = time.monotonic() - sent
    assert child.returncode == 0, err
    assert "interrupted after" in out, out + err
    assert "then " in out and "then 0 triangles" not in out, out
    assert waited < 2.0, "the call went on for %.2f s after Ctrl-C" % waited
