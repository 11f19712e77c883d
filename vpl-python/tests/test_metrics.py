"""The metrics on NumPy arrays against their definitions."""

import numpy as np
import pytest

import vpl


def test_rel_mse_and_rmse_follow_their_definitions():
    rng = np.random.default_rng(0)
    a = rng.random((6, 5, 3), dtype=np.float32)
    b = rng.random((6, 5, 3), dtype=np.float32)
    assert vpl.rel_mse(a, a) == 0
    want = np.mean((a.astype(np.float64) - b) ** 2 / (b.astype(np.float64) ** 2 + 0.01))
    assert vpl.rel_mse(a, b) == pytest.approx(want, rel=1e-5)
    assert vpl.rmse(a, b) == pytest.approx(np.sqrt(np.mean((a.astype(np.float64) - b) ** 2)), rel=1e-5)
    with pytest.raises(vpl.VplError):
        vpl.rel_mse(a, b[:3])
    with pytest.raises(vpl.VplError, match="shape"):
        vpl.rmse(a[..., :2], b[..., :2])


def test_temporal_error_is_the_papers_e_and_e_prime():
    est = np.array([[0.1, 0.2], [0.3, 0.1], [0.2, 0.2]])
    truth = np.array([[0.1, 0.1], [0.1, 0.1], [0.1, 0.1]])
    t = vpl.temporal_error(est, truth)
    err = est - truth
    assert t["e"] == pytest.approx(np.abs(err).mean())
    assert t["e_prime"] == pytest.approx(np.abs(np.diff(err, axis=0)).mean())
    assert t["bias"] == pytest.approx(err.mean())
    assert t["count"] == 6 and t["count_prime"] == 4
    with pytest.raises(vpl.VplError):
        vpl.temporal_error(est, truth[:2])


def test_compare_and_tone_mapping():
    rng = np.random.default_rng(1)
    a = rng.random((4, 4, 3), dtype=np.float32) + 0.5
    se = np.full_like(a, 0.1)
    c = vpl.compare(a, se, a, se)
    assert c["pass_rate"] == 1.0 and c["pixels"] == 16 and c["z"].shape == (4, 4)
    assert np.all(c["z"] == 0)
    c = vpl.compare(a + 1.0, se, a, se)
    assert c["pass_rate"] == 0.0 and np.all(np.array(c["mean_z"]) > 4)
    with pytest.raises(vpl.VplError, match="alpha"):
        vpl.compare(a, se, a, se, alpha=2)
    lum = 0.2126 * a[..., 0] + 0.7152 * a[..., 1] + 0.0722 * a[..., 2]
    assert np.allclose(vpl.tone_mapped_luminance(a), lum / (1 + lum), rtol=1e-6)
    assert vpl.tone_mapped_luminance(a[0, 0]).shape == ()
