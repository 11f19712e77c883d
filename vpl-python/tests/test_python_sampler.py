"""Samplers written in Python, in the toolkit's renderer."""

import numpy as np
import pytest

import vpl

from conftest import mean_se


class UniformArea:
    """VPLs uniform by area with flux L(y) / (N p(y)) (the toolkit's
    uniform-area example, in Python). Fresh points every frame."""

    def __init__(self):
        self.frames = []

    def next_frame(self, frame):
        self.frames.append(frame.index)
        n = frame.vpls
        pts = frame.scene.sample_area(n, seed=frame.seed * 1000 + frame.index)
        L = frame.scene.radiosity(pts, paths=16, max_bounces=2, seed=frame.seed * 1000 + frame.index)
        return pts["position"], pts["normal"], L / (n * pts["pdf"])


def test_a_python_sampler_brings_the_path_tracers_indirect_light(cornell):
    """Unbiased VPLs, unclamped, ray-traced and shaded exhaustively: the
    image mean over 8 seeds against the path tracer's indirect light
    (depth 5) through the pixel centres, which the G-buffer shades. The
    error combines the spread over seeds (7 degrees of freedom) and the path
    tracer's own; |t| within 4 fails with probability about 0.5 %."""
    size = (16, 16)
    means = []
    for seed in range(8):
        r = vpl.Renderer(
            cornell,
            sampler=UniformArea(),
            vpls=256,
            mode="indirect",
            visibility="raytraced",
            shading="exhaustive",
            clamp="off",
            seed=seed,
            size=size,
        )
        means.append(r.frame(0).mean(axis=(0, 1)))
        v = r.vpls()
        assert len(v) == 256 and r.sampler == "UniformArea"
    vm, vse = mean_se(np.array(means))
    # Path tracer through the pixel centres: the VPL renderer's points.
    pixels = [(x, y) for y in range(size[1]) for x in range(size[0])]
    pt, pt_se = vpl.track(cornell, pixels, spp=128, mode="indirect", size=size, seed=11, footprint="centre")
    n = len(pixels)
    ptm = pt.mean(axis=0)
    ptse = np.sqrt((pt_se**2).sum(axis=0)) / n
    z = (vm - ptm) / np.sqrt(vse**2 + ptse**2)
    assert np.all(np.abs(z) < 4), (vm, ptm, z)
    # A sampler that sent nothing would be 100 % off; one counted twice +100 %.
    assert np.all(np.abs(vm / ptm - 1) < 0.25)


class Fixed:
    """The same points every frame, fluxes scaled by the frame: nothing moves."""

    def __init__(self, scene, n):
        self.pts = scene.sample_area(n, seed=1)

    def next_frame(self, frame):
        n = len(self.pts["position"])
        flux = np.full((n, 3), 0.01 * (frame.index + 1), dtype=np.float32)
        return {"position": self.pts["position"], "normal": self.pts["normal"], "flux": flux}


def test_moved_slots_follow_what_the_sampler_returns(cornell):
    r = vpl.Renderer(cornell, sampler=Fixed(cornell, 40), vpls=64, size=(8, 8), mode="indirect")
    r.frame(0)
    v = r.vpls()
    assert len(v) == 40 and v["moved"].all() and np.array_equal(v["slot"], np.arange(40))
    r.frame(1)
    v = r.vpls()
    assert not v["moved"].any() and r.stats()["moved"] == 0
    assert np.allclose(v["flux"], 0.02)


class Marked:
    """Fixed points; slot 0 declared moved every frame, slot 1 moved
    without saying so from the third frame on."""

    def __init__(self, scene):
        self.pts = scene.sample_area(4, seed=2)
        self.calls = 0

    def next_frame(self, frame):
        self.calls += 1
        p = self.pts["position"].copy()
        if self.calls >= 3:
            p[1] += 0.01
        moved = np.array([True, False, False, False])
        return p, self.pts["normal"], np.full((4, 3), 0.01, dtype=np.float32), moved


def test_moved_flags_force_a_move_and_guard_against_an_unmarked_one(cornell):
    r = vpl.Renderer(cornell, sampler=Marked(cornell), vpls=4, size=(8, 8), mode="indirect")
    r.frame(0)
    r.frame(1)
    v = r.vpls()
    # Slot 0 moved where it stood: a new VPL (its shadow map is made anew).
    assert v["moved"].tolist() == [True, False, False, False] and r.stats()["moved"] == 1
    assert v["id"][0] != v["id"][1]
    with pytest.raises(vpl.VplError, match="VPL 1 is marked not moved"):
        r.frame(2)


class Broken:
    def __init__(self, out):
        self.out = out

    def next_frame(self, frame):
        if isinstance(self.out, Exception):
            raise self.out
        return self.out


def test_a_python_samplers_errors_reach_the_caller(cornell):
    r = vpl.Renderer(cornell, sampler=Broken(ZeroDivisionError("mine")), vpls=8, size=(8, 8))
    with pytest.raises(ZeroDivisionError, match="mine"):
        r.frame(0)
    p = np.zeros((9, 3), dtype=np.float32)
    r = vpl.Renderer(cornell, sampler=Broken((p, p, p)), vpls=8, size=(8, 8))
    with pytest.raises(vpl.VplError, match="budget of 8"):
        r.frame(0)
    r = vpl.Renderer(cornell, sampler=Broken((p[:2], p[:3], p[:2])), vpls=8, size=(8, 8))
    with pytest.raises(vpl.VplError, match="2 positions, 3 normals"):
        r.frame(0)
    r = vpl.Renderer(cornell, sampler=Broken((p[:2], p[:2], p[:2])), vpls=8, size=(8, 8))
    with pytest.raises(vpl.VplError, match="nonzero normal"):
        r.frame(0)
    r = vpl.Renderer(cornell, sampler=Broken("no"), vpls=8, size=(8, 8))
    with pytest.raises(vpl.VplError, match="must return"):
        r.frame(0)
    with pytest.raises(vpl.VplError, match="next_frame"):
        vpl.Renderer(cornell, sampler=object())
    with pytest.raises(vpl.VplError, match="reads no parameters"):
        vpl.Renderer(cornell, sampler=Fixed(cornell, 4), m_max=3)
