"""Long calls release the GIL and stop on Ctrl-C."""

import os
import signal
import threading
import time

import pytest

import vpl


def test_ctrl_c_stops_a_long_render(cornell):
    """A render of several minutes, interrupted after 0.5 s by SIGINT (what
    Ctrl-C sends): KeyboardInterrupt within a few seconds (each thread
    finishes the pixel it is on: 20,000 paths)."""
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    t0 = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        vpl.render_path(cornell, spp=20000, size=(128, 128))
    took = time.monotonic() - t0
    timer.cancel()
    assert took < 10, took


def test_renders_release_the_gil(cornell):
    """While another thread renders, this one keeps running Python code."""
    ticks = 0
    done = threading.Event()

    def render():
        vpl.render_path(cornell, spp=512, size=(32, 32))
        done.set()

    th = threading.Thread(target=render)
    th.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    th.join()
    assert ticks > 20, ticks
