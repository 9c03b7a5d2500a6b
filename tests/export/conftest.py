"""Shared fixtures of the runtime-bundle tests: bundles exported once per session."""

import numpy as np
import pytest

from profiles import example_profile_path
from workbench.hyperspectral import synthesize_cube
from workbench.hyperspectral.synthetic import PAPER_CUBE_WAVELENGTHS
from workbench.profile import load_profile

BUNDLE_LIGHTS = ("cie-d65", "cie-a", "d65-two-peak")


@pytest.fixture(scope="session")
def paint_cube():
    """48 × 40 texels of ColorChecker + CIE 2017 reflectances mixed smoothly."""
    return synthesize_cube(48, 40, cell=8, seed=11)


@pytest.fixture(scope="session")
def unseen_cube():
    """A cube of materials in neither the ColorChecker nor the CIE 2017 set (CIE TCS, NIST CQS)."""
    from workbench.hyperspectral.materials import material_reflectances

    spectra = np.vstack([material_reflectances("cie-tcs", PAPER_CUBE_WAVELENGTHS),
                         material_reflectances("nist-cqs-vs", PAPER_CUBE_WAVELENGTHS)])
    return synthesize_cube(48, 40, cell=8, seed=5, reflectances=spectra,
                           materials="CIE TCS + NIST CQS")


@pytest.fixture(scope="session")
def simulated_profile():
    """The shipped simulated-headset profile: extended model with channel interaction (not separable)."""
    return load_profile(example_profile_path("simulated-headset"))


@pytest.fixture(scope="session")
def vive_profile():
    return load_profile(example_profile_path("htc-vive-paper"))


def _bundle(tmp_path_factory, name, profile, cube):
    """(directory, summary) of ``profile``'s bundle with :data:`BUNDLE_LIGHTS` and the paint cube."""
    from workbench.export import write_bundle

    directory = tmp_path_factory.mktemp("bundles") / name
    return directory, write_bundle(profile, directory, light_ids=BUNDLE_LIGHTS,
                                   cubes=[("paint", cube)])


@pytest.fixture(scope="session")
def simulated_bundle(tmp_path_factory, simulated_profile, paint_cube):
    return _bundle(tmp_path_factory, "simulated", simulated_profile, paint_cube)


@pytest.fixture(scope="session")
def vive_bundle(tmp_path_factory, vive_profile, paint_cube):
    return _bundle(tmp_path_factory, "vive", vive_profile, paint_cube)
