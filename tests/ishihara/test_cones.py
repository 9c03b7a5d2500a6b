import numpy as np
import pytest

from workbench.colorimetry import WORKING_WAVELENGTHS, observer_cmfs
from workbench.ishihara.cones import (
    LMS_to_XYZ,
    XYZ_to_LMS,
    cone_fundamental_shifted_StockmanSharpe2000,
    cone_fundamentals_Smith_Pokorny1975,
    cone_fundamentals_StockmanSharpe2000,
    confusion_line_residual,
    copunctal_point,
    photopigment_peaks_StockmanSharpe2000,
)


@pytest.mark.parametrize("deficiency, published", [
    ("protan", (0.7465, 0.2535)),   # Wyszecki & Stiles (1982); Viénot et al. (1999)
    ("deutan", (1.40, -0.40)),
    ("tritan", (0.1748, 0.0)),
])
def test_copunctal_points_are_the_published_ones(deficiency, published):
    assert copunctal_point(deficiency) == pytest.approx(published, abs=5e-4)


def test_unknown_deficiency_names_the_valid_ones():
    with pytest.raises(ValueError, match="deutan"):
        copunctal_point("achromat")


def test_fundamentals_are_linear_in_cie1931_and_l_plus_m_is_y():
    fundamentals = cone_fundamentals_Smith_Pokorny1975()
    cmfs = observer_cmfs().values
    assert fundamentals.shape == (401, 3)
    np.testing.assert_allclose(fundamentals[:, 0] + fundamentals[:, 1], cmfs[:, 1], atol=1e-4)
    XYZ = np.array([[0.2, 0.3, 0.4], [50.0, 40.0, 10.0]])
    np.testing.assert_allclose(LMS_to_XYZ(XYZ_to_LMS(XYZ)), XYZ, atol=1e-12)


def test_confusion_line_residual_is_zero_along_a_line_and_not_across():
    point = copunctal_point("protan")
    a = np.array([0.35, 0.38])
    on_line = point + 0.5 * (a - point)
    assert confusion_line_residual(a, on_line, "protan") == pytest.approx(0, abs=1e-12)
    assert confusion_line_residual(a, [0.35, 0.36], "protan") > 1e-3


def _linear_fit_residual(fundamentals, cmfs):
    """Relative residual of each fundamental's best fit by a linear combination of x̄, ȳ, z̄."""
    coefficients, *_ = np.linalg.lstsq(cmfs, fundamentals, rcond=None)
    return np.linalg.norm(cmfs @ coefficients - fundamentals, axis=0) / \
        np.linalg.norm(fundamentals, axis=0)


def test_stockman_sharpe_fundamentals_are_not_linear_in_cie1931_smith_pokorny_are():
    cmfs = observer_cmfs("cie1931-2").values
    assert _linear_fit_residual(cone_fundamentals_Smith_Pokorny1975(), cmfs).max() < 1e-3
    residual = _linear_fit_residual(cone_fundamentals_StockmanSharpe2000(), cmfs)
    assert residual[0] > 0.01 and residual[1] > 0.01 and residual[2] > 0.05
    fundamentals = cone_fundamentals_StockmanSharpe2000()
    assert fundamentals.shape == (401, 3) and np.all(fundamentals > 0)
    assert fundamentals.max(axis=0) == pytest.approx([1, 1, 1])
    assert WORKING_WAVELENGTHS[fundamentals.argmax(axis=0)].tolist() == [570, 543, 442]


def _long_half_maximum_nm(fundamental):
    """Where the long-wavelength flank falls to half the peak (robust, unlike the flat top)."""
    peak = int(np.argmax(fundamental))
    flank, wavelengths = fundamental[peak:], WORKING_WAVELENGTHS[peak:]
    below = int(np.argmax(flank < 0.5))
    return float(np.interp(0.5, flank[below::-1], wavelengths[below::-1]))


@pytest.mark.parametrize("cone, shift", [(0, -10.0), (0, -20.0), (1, 12.0)])
def test_a_pigment_shift_moves_the_fundamental_and_renormalises_it(cone, shift):
    normal = cone_fundamentals_StockmanSharpe2000()[:, cone]
    shifted = cone_fundamental_shifted_StockmanSharpe2000(cone, shift)
    assert shifted.max() == pytest.approx(1.0)
    # the pigment moves on a log-wavelength axis: the flank at λ moves by Δλ · λ / λ_max
    lambda_max = photopigment_peaks_StockmanSharpe2000()[cone]
    half = _long_half_maximum_nm(normal)
    moved = _long_half_maximum_nm(shifted) - half
    assert moved == pytest.approx(shift * half / lambda_max, rel=0.1)
    # a translation, not a blend: the curve is not a mixture of the normal L and M
    both = cone_fundamentals_StockmanSharpe2000()[:, :2]
    assert _linear_fit_residual(shifted[:, None], both)[0] > 0.01
    np.testing.assert_allclose(cone_fundamental_shifted_StockmanSharpe2000(cone, 0.0), normal,
                               rtol=1e-12)


def test_moving_the_l_pigment_onto_the_m_pigment_gives_the_m_fundamental():
    peak_L, peak_M, rms = photopigment_peaks_StockmanSharpe2000()
    assert 545 < peak_L < 565 and 515 < peak_M < 535 and rms < 0.02
    L_as_M = cone_fundamental_shifted_StockmanSharpe2000(0, peak_M - peak_L)
    np.testing.assert_allclose(L_as_M, cone_fundamentals_StockmanSharpe2000()[:, 1], atol=0.02)


def test_pigment_shift_rejects_s_and_huge_shifts():
    with pytest.raises(ValueError, match="L \\(0\\) and M \\(1\\)"):
        cone_fundamental_shifted_StockmanSharpe2000(2, 5.0)
    with pytest.raises(ValueError, match="40 nm"):
        cone_fundamental_shifted_StockmanSharpe2000(0, -80.0)
