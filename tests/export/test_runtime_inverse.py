"""The display inverse in the runtime's form against each model's own inverse."""

import numpy as np
import pytest

from workbench.display import GammaMatrixDisplay, SRGBDisplay
from workbench.errors import InputError
from workbench.export import runtime_display_inverse
from workbench.export.runtime_inverse import UNREACHED_THRESHOLD, sample_trilinear


def _random_colours(display, count=50000, seed=3):
    rgb = np.random.default_rng(seed).uniform(0, 255, (count, 3))
    return display.forward(rgb)


@pytest.mark.parametrize("which", ["vive", "srgb"])
def test_separable_models_need_no_correction_and_match_their_inverse(request, which):
    display = (SRGBDisplay() if which == "srgb"
               else request.getfixturevalue("vive_profile").display_model())
    inverse = runtime_display_inverse(display)
    assert inverse.correction is None
    XYZ = _random_colours(display)
    same = np.all(inverse.dac(XYZ) == display.inverse_rgb8(XYZ), axis=-1)
    assert np.mean(same) >= 0.9999
    assert np.all(np.abs(inverse.dac(XYZ) - display.inverse_rgb8(XYZ)) <= 1)


def test_channel_interaction_is_carried_by_the_correction_table(simulated_profile):
    display = simulated_profile.display_model()
    inverse = runtime_display_inverse(display)
    assert inverse.correction is not None and inverse.correction.shape == (61, 61, 61, 3)
    XYZ = _random_colours(display)
    exact = display.inverse_rgb8(XYZ)
    with_table = inverse.dac(XYZ)
    assert np.mean(np.all(with_table == exact, axis=-1)) >= 0.99
    assert np.abs(with_table - exact).max() <= 1
    # without the table the interaction costs many counts: the table does the work
    affine_only = runtime_display_inverse(display)
    object.__setattr__(affine_only, "correction", None)
    assert np.abs(affine_only.dac(XYZ) - exact).max() >= 3


def test_thresholds_rise_and_mark_unreached_levels():
    display = GammaMatrixDisplay(gamma=[2.2, 2.2, 2.2], matrix=np.diag([40.0, 50.0, 10.0]),
                                 white=[40.0, 50.0, 10.0])
    thresholds = runtime_display_inverse(display).thresholds
    assert thresholds.shape == (3, 255) and thresholds.dtype == np.float32
    assert np.all(np.diff(thresholds, axis=1) >= 0)
    assert np.all(thresholds <= 1.0)

    class Dim(SRGBDisplay):                      # never drives past DAC 250
        def dac_from_drive(self, drive):
            return 250.0 * np.clip(np.asarray(drive, dtype=float), 0, 1)

    dim = runtime_display_inverse(Dim()).thresholds
    assert np.all(dim[:, :250] <= 1.0)
    assert np.all(dim[:, 250:] == UNREACHED_THRESHOLD)


def test_trilinear_sampling_is_exact_on_a_linear_table():
    nodes = np.linspace(0, 1, 5)
    b, g, r = np.meshgrid(nodes, nodes, nodes, indexing="ij")
    table = np.stack([r, 2 * g, r + g + b], axis=-1)
    points = np.random.default_rng(1).uniform(0, 1, (100, 3))
    expected = np.stack([points[:, 0], 2 * points[:, 1], points.sum(axis=1)], axis=-1)
    np.testing.assert_allclose(sample_trilinear(table, points), expected, atol=1e-6)


def test_a_model_whose_curve_mixes_channels_is_refused():
    class Mixed(SRGBDisplay):
        def dac_from_drive(self, drive):
            drive = np.asarray(drive, dtype=float)
            return 255.0 * np.clip(drive + 0.1 * drive[..., ::-1], 0, 1)

    with pytest.raises(InputError, match="not one non-decreasing curve per channel"):
        runtime_display_inverse(Mixed())
