"""vpl.render_path: arrays, determinism, modes, bad input."""

import numpy as np
import pytest

import vpl


def test_render_path_returns_images_and_standard_errors(cornell):
    img, se = vpl.render_path(cornell, spp=16, size=(24, 16), seed=1)
    assert img.shape == (16, 24, 3) and se.shape == (16, 24, 3)
    assert img.dtype == np.float32 and se.dtype == np.float32
    assert img.flags["C_CONTIGUOUS"] and img.flags["OWNDATA"] is not None
    assert np.all(np.isfinite(img)) and img.mean() > 0 and np.all(se >= 0)
    again, _ = vpl.render_path(cornell, spp=16, size=(24, 16), seed=1)
    assert np.array_equal(img, again)
    other, _ = vpl.render_path(cornell, spp=16, size=(24, 16), seed=2)
    assert not np.array_equal(img, other)


def test_full_light_is_direct_plus_indirect_within_the_noise(cornell):
    kw = dict(spp=64, size=(16, 16), max_depth=5)
    full, full_se = vpl.render_path(cornell, mode="full", seed=1, **kw)
    direct, direct_se = vpl.render_path(cornell, mode="direct", seed=2, **kw)
    indirect, indirect_se = vpl.render_path(cornell, mode="indirect", seed=3, **kw)
    # Image means of independent renders: the difference over its standard
    # error (pixels independent) within 4.
    n = full.shape[0] * full.shape[1]
    for c in range(3):
        diff = full[..., c].mean() - direct[..., c].mean() - indirect[..., c].mean()
        se = np.sqrt((full_se[..., c] ** 2).sum() + (direct_se[..., c] ** 2).sum() + (indirect_se[..., c] ** 2).sum()) / n
        assert abs(diff) < 4 * se + 1e-6, (c, diff, se)


def test_bad_arguments_raise(cornell):
    with pytest.raises(vpl.VplError, match="spp"):
        vpl.render_path(cornell, spp=0)
    with pytest.raises(vpl.VplError, match="unknown mode"):
        vpl.render_path(cornell, mode="sideways")
    with pytest.raises(vpl.VplError):
        vpl.render_path(cornell, size=(0, 4))
    with pytest.raises(vpl.VplError, match="materials"):
        vpl.render_path(cornell, materials="wood")


def test_progress_bar_draws_when_asked(cornell, capsys):
    pytest.importorskip("tqdm")
    vpl.render_path(cornell, spp=4, size=(16, 16), progress=True)
    assert "path tracing" in capsys.readouterr().err
