"""Long calls release the GIL and stop on Ctrl-C."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import vpl


@pytest.fixture(autouse=True)
def ctrl_c_raises():
    """SIGINT raises KeyboardInterrupt during each test, as in a terminal.

    A process started in the background of a non-interactive shell inherits
    SIGINT ignored, and Python then installs no handler of its own: the
    signal these tests send would be lost. The test's handler is restored
    afterwards."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


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


def _interrupt_after(seconds):
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def test_ctrl_c_stops_tracking(cornell):
    """Path tracing a few pixels with 10⁸ paths each (minutes), interrupted
    after 0.5 s: KeyboardInterrupt within a few seconds (each thread ends
    the batch of 4096 paths it is on)."""
    t0 = time.monotonic()
    timer = _interrupt_after(0.5)
    with pytest.raises(KeyboardInterrupt):
        vpl.track(cornell, [(10, 10), (20, 20)], spp=100_000_000, size=(32, 32))
    timer.cancel()
    assert time.monotonic() - t0 < 10


class SlowSampler:
    """4096 VPLs after a second's thought (time.sleep releases the GIL, as
    NumPy work would)."""

    def next_frame(self, frame):
        time.sleep(1.0)
        n = frame.vpls
        pts = frame.scene.sample_area(n, seed=frame.index)
        return pts["position"], pts["normal"], np.full((n, 3), 1e-3, dtype=np.float32)


def test_ctrl_c_stops_a_frame_between_stages(cornell):
    """A frame whose shading alone casts 512·512·4096 shadow rays (half a
    minute on two cores; 1/16 of it measured 0.57 s), interrupted during the
    sampler's second: the frame stops at the next stage boundary (after the
    visibility update) and raises KeyboardInterrupt within a few seconds
    instead of shading."""
    r = vpl.Renderer(cornell, sampler=SlowSampler(), vpls=4096, visibility="raytraced", shading="exhaustive", mode="indirect", clamp="off", size=(512, 512))
    t0 = time.monotonic()
    timer = _interrupt_after(0.3)
    with pytest.raises(KeyboardInterrupt):
        r.frame(0)
    timer.cancel()
    assert time.monotonic() - t0 < 6
