"""Shared fixtures of the vpl package's tests."""

import numpy as np
import pytest

import vpl


@pytest.fixture(scope="session")
def cornell():
    return vpl.Scene.load("cornell")


def mean_se(values):
    """Mean and standard error of the mean of independent values (rows)."""
    v = np.asarray(values, dtype=np.float64)
    return v.mean(axis=0), v.std(axis=0, ddof=1) / np.sqrt(len(v))
