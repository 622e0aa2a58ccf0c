"""Ctrl-C during a long call: SIGINT sent to a fresh interpreter in the middle
of a call (the first render of that interpreter among them) raises
KeyboardInterrupt within a second, never a PanicException, returns nothing,
and leaves the module usable."""

import os
import select
import signal
import subprocess
import sys
import time

import pytest

# Each call takes far longer than the test waits (measured on 2 loaded cores:
# series and metric of the 4e6 samples about 20 s, frames about 70 s,
# simulate about 8 s, the renders hours): if it is not stopped, the child
# prints "finished" (or nothing for ANSWER_S) and the test fails.
CHILD = r"""
import signal, sys, time
import numpy as np
import mmbm

# Python's own Ctrl-C handler, whatever the child inherited: a process
# started in the background by a shell without job control (`cmd &` in a
# script, as `nohup ... &` runs CI) starts with SIGINT ignored, and Python
# then installs no handler, so the signal would never arrive.
signal.signal(signal.SIGINT, signal.default_int_handler)

which = sys.argv[1]
n = 4_000_000
t = np.arange(n) / 1000.0
w = np.random.default_rng(1).normal(0, 1, (n, 3))
calls = {
    "render": lambda: mmbm.render(omega=[3, -2, 5], resolution=(4096, 3072), quality="4096:0.05",
                                  integrator="lattice", backend="cpu"),
    "render_maps": lambda: mmbm.render(omega=[3, -2, 5], resolution=(4096, 3072), quality="fast",
                                       backend="cpu", maps=True),
    "series": lambda: mmbm.series(t, w, method="exact:1e-12"),
    "frames": lambda: mmbm.frames(t, w, t_start=np.arange(0.0, 3900.0, 0.01), exposure_s=0.5),
    "simulate": lambda: mmbm.simulate("moderate", duration=2e4, rate=1000.0),
    "metric": lambda: mmbm.metric(w, method="exact:1e-12"),
}
print("ready", flush=True)
t0 = time.monotonic()
try:
    calls[which]()
    print("finished after %.1f s" % (time.monotonic() - t0), flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    # Still usable: a small call of the same kind works.
    m = mmbm.metric([0.1, 0.2, 0.3])
    img, _ = mmbm.render(omega=[0.3, 0, 0], resolution=(16, 12), quality="fast", maps=False)
    print("usable", float(m) > 0 and img.shape == (12, 16, 3), flush=True)
"""

WAIT_S = 0.8  # into the call before Ctrl-C
LIMIT_S = 3.0  # from Ctrl-C to KeyboardInterrupt
ANSWER_S = 60.0  # the longest the test waits for any answer to Ctrl-C


@pytest.mark.parametrize("which", ["render", "render_maps", "series", "frames", "simulate", "metric"])
def test_ctrl_c_interrupts_a_long_call(which):
    p = subprocess.Popen(
        [sys.executable, "-c", CHILD, which],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        assert p.stdout.readline().strip() == "ready", p.stderr.read()
        time.sleep(WAIT_S)
        assert p.poll() is None, "the call ended before the interrupt: make it longer"
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        # Bounded: a child that does not stop must fail the test, not hang it.
        answered, _, _ = select.select([p.stdout], [], [], ANSWER_S)
        assert answered, f"{which}: no answer {ANSWER_S} s after SIGINT"
        line = p.stdout.readline().strip()
        took = time.monotonic() - sent
        rest, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert "PanicException" not in err and "panicked" not in err, err
    assert line == "interrupted", (line, err)
    assert took < LIMIT_S, f"{which}: KeyboardInterrupt {took:.2f} s after SIGINT"
    assert rest.strip() == "usable True", (rest, err)
    assert p.returncode == 0, err


def test_a_handler_that_does_not_raise_lets_the_call_finish():
    """A SIGINT handler of the program's own that returns (no exception) runs
    during the call, which then finishes with its full result: the first
    render of the interpreter, whose arrays are the first the module makes
    (no panic about the NumPy capsule)."""
    code = (
        "import mmbm, signal, sys\n"
        "hits = []\n"
        "signal.signal(signal.SIGINT, lambda *a: hits.append(1))\n"
        "print('ready', flush=True)\n"
        "img, maps = mmbm.render(omega=[3, -2, 5], resolution=(128, 96), quality='4096:0.05', backend='cpu')\n"
        "print(len(hits) > 0, img.shape, sorted(maps), flush=True)\n"
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "ready", p.stderr.read()
        time.sleep(0.3)
        assert p.poll() is None, "the render ended before the signal: make it longer"
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=300)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert "PanicException" not in err and "panicked" not in err, err
    assert out.strip() == "True (96, 128, 3) ['disp_px', 'path_px', 'speed_px_s']", (out, err)
    assert p.returncode == 0, err
