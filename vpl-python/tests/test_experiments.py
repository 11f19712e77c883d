"""vpl.sequence and vpl.compare_samplers (a small Table 1), with a Python sampler among the built-ins."""

import numpy as np
import pytest

import vpl

from test_python_sampler import UniformArea


def test_sequence_follows_the_tracked_pixels_over_the_animation():
    office = vpl.Scene.load("office")
    s = vpl.sequence(office, frames=range(3), size=(32, 24), sampler="ir", vpls=64, images=True)
    assert s["pixels"] == vpl.default_tracked_pixels(32, 24) and len(s["pixels"]) == 8
    assert s["tracked"].shape == (3, 8, 3) and s["images"].shape == (3, 24, 32, 3)
    xs, ys = zip(*s["pixels"])
    assert np.array_equal(s["tracked"][2], s["images"][2][list(ys), list(xs)])
    assert s["time"][1] == pytest.approx(1 / office.fps)
    assert len(s["stats"]) == 3 and s["moved"][0] > 0
    with pytest.raises(vpl.VplError, match="outside"):
        vpl.sequence(office, frames=[0], tracked=[(40, 1)], size=(32, 24), sampler="ir", vpls=8)
    with pytest.raises(vpl.VplError, match="no frames"):
        vpl.sequence(office, frames=[], sampler="ir")


def test_a_small_table1_with_a_python_sampler(cornell):
    """On a still view, a sampler that draws fresh VPLs every frame
    flickers and SMC does not: the Python sampler's |E′| was 7× SMC's here
    (0.0096 against 0.0013 over 2 seeds); the test asks for 3×. |E| and |E′|
    are recomputed from the rows' own values against the truth."""
    res = vpl.compare_samplers(
        cornell,
        {"smc": "smc", "uniform": UniformArea},
        frames=range(6),
        size=(32, 24),
        truth_spp=2048,
        seeds=2,
        vpls=256,
        visibility="raytraced",
        clamp="off",
    )
    rows = res["rows"]
    assert res["truth"].shape == (6, 8)
    for name, row in rows.items():
        assert row["values"].shape == (2, 6, 8)
        again = np.mean([vpl.temporal_error(v, res["truth"])["e"] for v in row["values"]])
        assert row["e"] == pytest.approx(again, rel=1e-12), name
        assert np.isfinite(row["e_se"])
    assert rows["uniform"]["e_prime"] > 3 * rows["smc"]["e_prime"]
