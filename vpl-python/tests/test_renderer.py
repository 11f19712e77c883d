"""vpl.Renderer with the registry's samplers: frames, VPL arrays, statistics, errors."""

import numpy as np
import pytest

import vpl


def test_samplers_lists_the_registry():
    names = [s["name"] for s in vpl.samplers()]
    for n in ["ir", "rr", "mir", "tcas", "smc", "smc-knn"]:
        assert n in names
    smc = next(s for s in vpl.samplers() if s["name"] == "smc")
    assert smc["about"] and any(k["key"] == "m-max" for k in smc["keys"])


def test_smc_frames_vpls_and_stats(cornell):
    r = vpl.Renderer(cornell, sampler="smc", vpls=128, size=(32, 24), mode="indirect", m_max=4, warmup=2)
    assert r.sampler == "smc" and r.backend == "cpu" and r.vpls_budget == 128 and r.device is None
    assert r.stats() == {} and r.indirect() is None
    first = r.frame(0)
    assert first.shape == (24, 32, 3) and first.dtype == np.float32 and first.mean() > 0
    v = r.vpls()
    assert set(v.dtype.names) == {"position", "normal", "flux", "slot", "moved", "id", "bounce"}
    assert len(v) == 128 and np.array_equal(np.sort(v["slot"]), np.arange(128))
    assert np.allclose(np.linalg.norm(v["normal"], axis=1), 1, atol=1e-4)
    r.frame(1)
    s = r.stats()
    for k in ["gbuffer_ms", "sampling_ms", "visibility_ms", "shading_ms", "direct_ms", "total_ms"]:
        assert s[k] >= 0
    assert s["frame"] == 1 and s["stored"] == 128
    # SMC moves at most M_max VPLs a frame after its warm-up.
    assert s["moved"] <= 4 and r.vpls()["moved"].sum() == s["moved"]
    assert "stored" in s["sampler"]
    assert r.indirect().shape == (24, 32, 3)


def test_the_same_settings_give_the_same_bits(cornell):
    a = vpl.Renderer(cornell, sampler="ir", vpls=64, size=(16, 16), seed=3)
    b = vpl.Renderer(cornell, sampler="ir", vpls=64, size=(16, 16), seed=3)
    assert np.array_equal(a.frame(0), b.frame(0))
    assert np.array_equal(a.vpls(), b.vpls())


def test_frames_return_images_only_when_asked(cornell):
    a = vpl.Renderer(cornell, sampler="ir", vpls=64, size=(16, 16), seed=3)
    b = vpl.Renderer(cornell, sampler="ir", vpls=64, size=(16, 16), seed=3)
    assert a.image() is None
    assert a.frame(0, image=False) is None
    assert np.array_equal(a.image(), b.frame(0))


def test_every_builtin_sampler_renders(cornell):
    for name in ["ir", "rr", "mir", "tcas", "smc", "smc-knn"]:
        r = vpl.Renderer(cornell, sampler=name, vpls=32, size=(8, 8), mode="indirect", visibility="raytraced")
        assert np.isfinite(r.frame(0)).all(), name


def test_auto_backend_is_a_device_that_opens_else_the_cpu(cornell):
    """`backend="auto"`, as on the command line: the first device that
    opens (a GPU build with an adapter), else the CPU."""
    r = vpl.Renderer(cornell, sampler="ir", vpls=16, size=(8, 8), backend="auto")
    assert r.backend in ("cpu", "gpu")
    assert (r.device is None) == (r.backend == "cpu")
    assert np.isfinite(r.frame(0)).all()


def test_lightcuts_shade_by_name(cornell):
    """`shading="lightcuts:N"`, as the command line spells it: a cut of N
    VPLs a pixel through a light tree; a cut of 0 is an error."""
    r = vpl.Renderer(cornell, sampler="ir", vpls=64, size=(16, 16), mode="indirect", visibility="raytraced", shading="lightcuts:8")
    img = r.frame(0)
    assert np.isfinite(img).all() and img.mean() > 0
    with pytest.raises(vpl.VplError, match="cut"):
        vpl.Renderer(cornell, shading="lightcuts:0")
    culled = vpl.Renderer(cornell, sampler="ir", vpls=64, size=(16, 16), mode="indirect", visibility="raytraced", shading="culled:4", clamp="off")
    assert np.isfinite(culled.frame(0)).all()
    with pytest.raises(vpl.VplError, match="culling bound"):
        vpl.Renderer(cornell, shading="culled:0")


def test_bad_settings_raise_vpl_errors(cornell):
    with pytest.raises(vpl.VplError, match="nope"):
        vpl.Renderer(cornell, sampler="nope")
    with pytest.raises(vpl.VplError, match="colour"):
        vpl.Renderer(cornell, sampler="smc", colour=3)
    with pytest.raises(vpl.VplError, match="visibility"):
        vpl.Renderer(cornell, visibility="x-ray")
    with pytest.raises(vpl.VplError, match="backend"):
        vpl.Renderer(cornell, backend="abacus")
    with pytest.raises(vpl.VplError, match="budget"):
        vpl.Renderer(cornell, vpls=0)
    with pytest.raises(vpl.VplError, match="clamp"):
        vpl.Renderer(cornell, clamp=-1.0)
    with pytest.raises(vpl.VplError, match="clamp"):
        vpl.Renderer(cornell, clamp="sometimes")
    office = vpl.Scene.load("office")
    r = vpl.Renderer(office, sampler="ir", vpls=16, size=(8, 8))
    with pytest.raises(vpl.VplError, match="past the animation"):
        r.frame(office.frame_count)
