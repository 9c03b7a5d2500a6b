"""Shared fixtures of the hyperspectral tests: small cubes, made of real reflectances."""

import numpy as np
import pytest

from workbench.hyperspectral import PAPER_CUBE_WAVELENGTHS, ReflectanceCube, synthesize_cube


@pytest.fixture(scope="session")
def small_cube() -> ReflectanceCube:
    """48 × 40 texels, 101 bands: ColorChecker + CIE 2017 samples mixed smoothly."""
    return synthesize_cube(48, 40, cell=8, seed=11)


@pytest.fixture
def random_cube(rng) -> ReflectanceCube:
    """6 × 5 × 101 uniform random reflectances (any value in [0, 1] must survive a round trip)."""
    data = rng.uniform(0.0, 1.0, (6, 5, PAPER_CUBE_WAVELENGTHS.size)).astype(np.float32)
    return ReflectanceCube(data, PAPER_CUBE_WAVELENGTHS, "random test cube")


@pytest.fixture(scope="session")
def unseen_cube() -> ReflectanceCube:
    """48 × 40 texels of materials the level-2 method was not tuned on: the CIE 13.3 test
    colour samples and the NIST CQS samples (Munsell chips, leaf, skin), mixed smoothly."""
    from workbench.hyperspectral.materials import material_reflectances

    spectra = np.vstack([material_reflectances("cie-tcs", PAPER_CUBE_WAVELENGTHS),
                         material_reflectances("nist-cqs-vs", PAPER_CUBE_WAVELENGTHS)])
    return synthesize_cube(48, 40, cell=8, seed=5, reflectances=spectra,
                           materials="CIE TCS + NIST CQS")
