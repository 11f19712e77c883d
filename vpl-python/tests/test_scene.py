"""vpl.Scene: loading, what a scene reports, its frames, bad input."""

import numpy as np
import pytest

import vpl


def test_builtin_cornell_reports_its_geometry_lights_and_camera(cornell):
    assert cornell.name == "cornell"
    assert cornell.triangles == 36
    assert cornell.frame == 0 and cornell.frame_count >= 1
    assert [l["type"] for l in cornell.lights].count("area") == 2  # the ceiling light's two triangles
    cam = cornell.camera
    assert cam["resolution"] == cornell.resolution
    assert len(cam["origin"]) == 3 and 0 < cam["fov"] < 180
    lo, hi = cornell.bounds
    assert all(a < b for a, b in zip(lo, hi))
    assert cornell.surface_area > 0
    assert "cornell" in vpl.Scene.builtins()
    assert "Scene('cornell'" in repr(cornell)


def test_an_animated_scene_moves_its_camera_between_frames():
    office = vpl.Scene.load("office")
    assert office.frame_count > 1 and office.fps > 0
    last = office.at(office.frame_count - 1)
    assert last.frame == office.frame_count - 1
    assert last.time == pytest.approx((office.frame_count - 1) / office.fps, rel=1e-5) or last.time > 0
    assert last.camera["origin"] != office.camera["origin"]
    with pytest.raises(vpl.VplError, match="past the scene's last frame"):
        office.at(office.frame_count)


def test_bad_scenes_raise_vpl_errors_with_the_loaders_message(tmp_path):
    with pytest.raises(vpl.VplError, match="nosuch"):
        vpl.Scene.load("nosuch")
    bad = tmp_path / "bad.toml"
    bad.write_text("[geometry]\nobj = 'missing.obj'\n")
    with pytest.raises(vpl.VplError, match="missing.obj"):
        vpl.Scene.load(str(bad))
    garbage = tmp_path / "g.obj"
    garbage.write_text("v 0 0 0\nv 1 0 0\nf 1 2 9\n")
    with pytest.raises(vpl.VplError):
        vpl.Scene.load(str(garbage))


def test_sample_area_is_uniform_by_area_and_seeded(cornell):
    a = cornell.sample_area(20000, seed=3)
    b = cornell.sample_area(20000, seed=3)
    assert np.array_equal(a["position"], b["position"])
    assert a["position"].shape == (20000, 3) and a["position"].dtype == np.float32
    assert a["triangle"].dtype == np.uint32 and a["barycentric"].shape == (20000, 2)
    # The unit normals of the chosen sides.
    assert np.allclose(np.linalg.norm(a["normal"], axis=1), 1, atol=1e-5)
    sides = 2 if cornell.two_sided else 1
    assert a["pdf"] == pytest.approx(1 / (sides * cornell.surface_area), rel=1e-6)
    # The floor (y ≈ 0 at the box's bottom) holds its share of the area: a
    # binomial count, 4 standard errors.
    lo, _ = cornell.bounds
    on_floor = np.abs(a["position"][:, 1] - lo[1]) < 0.02
    share = on_floor.mean()
    assert 0.05 < share < 0.5
    c = cornell.sample_area(20000, seed=4)
    share_c = (np.abs(c["position"][:, 1] - lo[1]) < 0.02).mean()
    se = np.sqrt(share * (1 - share) / 20000 * 2)
    assert abs(share - share_c) < 4 * se


def test_radiosity_is_seeded_and_refuses_bad_points(cornell):
    pts = cornell.sample_area(64, seed=1)
    l1 = cornell.radiosity(pts, paths=8, seed=5)
    l2 = cornell.radiosity(pts, paths=8, seed=5)
    assert l1.shape == (64, 3) and np.array_equal(l1, l2)
    assert np.all(l1 >= 0) and l1.sum() > 0
    with pytest.raises(vpl.VplError, match="triangle"):
        cornell.radiosity({"barycentric": pts["barycentric"], "flipped": pts["flipped"]})
    bad = dict(pts)
    bad["triangle"] = pts["triangle"] + np.uint32(1000)
    with pytest.raises(vpl.VplError, match="past the scene"):
        cornell.radiosity(bad)
    with pytest.raises(vpl.VplError, match="at least 1 path"):
        cornell.radiosity(pts, paths=0)
