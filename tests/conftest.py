"""Shared fixtures. Tests run headless; nothing here touches the network."""

import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(20201001)
