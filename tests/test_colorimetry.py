import colour
import numpy as np
import pytest

from workbench.colorimetry import (
    WORKING_WAVELENGTHS,
    XYZ_relative_weights,
    as_reflectances,
    as_spectral_distribution,
    delta_E2000,
    observer_cmfs,
    reflectances_to_XYZ_relative,
    white_XYZ_relative,
)
from workbench.errors import InputError

D65 = colour.SDS_ILLUMINANTS["D65"]


def test_d65_perfect_diffuser_at_k_085_matches_the_paper():
    # Paper Table 3: CIE D65 at 85 % of the display white → XYZ (80.81, 85.00, 92.57).
    XYZ = white_XYZ_relative(D65, k=0.85, Y_white=100.0)
    np.testing.assert_allclose(XYZ, [80.81, 85.00, 92.57], atol=0.1)


def test_scale_is_k_times_display_white():
    XYZ = white_XYZ_relative(colour.SDS_ILLUMINANTS["A"], k=0.5, Y_white=240.0)
    assert XYZ[1] == pytest.approx(120.0)


def test_weights_agree_with_colour_science_integration():
    patches = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    sd = list(patches.values())[5]
    ours = reflectances_to_XYZ_relative(sd, D65, k=1.0, Y_white=100.0)[0]
    shape = colour.SpectralShape(380, 780, 1)
    theirs = colour.sd_to_XYZ(sd.copy().align(shape), cmfs=observer_cmfs("cie1931-2"),
                              illuminant=D65.copy().align(shape), method="Integration")
    np.testing.assert_allclose(ours, theirs, rtol=1e-9)


def test_observer_choice_changes_the_result():
    sd = list(colour.SDS_COLOURCHECKERS["BabelColor Average"].values())[1]
    two = reflectances_to_XYZ_relative(sd, D65, "cie1931-2")
    ten = reflectances_to_XYZ_relative(sd, D65, "cie1964-10")
    assert not np.allclose(two, ten, atol=0.05)
    with pytest.raises(InputError, match="unknown observer"):
        reflectances_to_XYZ_relative(sd, D65, "cie2099-7")


def test_nd_reflectances_and_resampling():
    flat = np.full((2, 3, WORKING_WAVELENGTHS.size), 0.5)
    XYZ = reflectances_to_XYZ_relative(flat.reshape(-1, WORKING_WAVELENGTHS.size), D65,
                                       k=1.0, Y_white=100.0)
    np.testing.assert_allclose(XYZ[:, 1], 50.0)
    coarse = as_reflectances(np.full(41, 0.2), wavelengths=np.arange(380, 781, 10))
    assert coarse.shape == (1, 401)
    np.testing.assert_allclose(coarse, 0.2)


@pytest.mark.parametrize("bad, message", [
    (np.array([]), "empty"),
    (np.full(401, np.nan), "NaN"),
    (np.full(401, -0.1), "negative"),
    (np.ones(17), "bands"),
])
def test_bad_reflectances_get_clear_errors(bad, message):
    with pytest.raises(InputError, match=message):
        reflectances_to_XYZ_relative(bad, D65)


def test_bad_spectra_and_scales():
    with pytest.raises(InputError, match="strictly increasing"):
        as_spectral_distribution([1, 2, 3], [400, 400, 500])
    with pytest.raises(InputError, match="negative"):
        as_spectral_distribution([1, -2, 3], [400, 500, 600])
    with pytest.raises(InputError, match="k="):
        XYZ_relative_weights(D65, k=0)
    with pytest.raises(InputError, match="Y_white"):
        XYZ_relative_weights(D65, Y_white=float("nan"))


# Sharma, Wu & Dalal (2005), "The CIEDE2000 color-difference formula:
# implementation notes, supplementary test data", pairs 1, 7, 17, 25 and 34.
SHARMA_PAIRS = [
    ((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
    ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
    ((50.0, 2.5, 0.0), (73.0, 25.0, -18.0), 27.1492),
    ((60.2574, -34.0099, 36.2677), (60.4626, -34.1751, 39.4387), 1.2644),
    ((22.7233, 20.0904, -46.6940), (23.0331, 14.9730, -42.5619), 2.0373),
]


@pytest.mark.parametrize("lab_a, lab_b, expected", SHARMA_PAIRS)
def test_delta_E2000_published_values(lab_a, lab_b, expected):
    white = np.array([95.047, 100.0, 108.883])
    xy_white = colour.XYZ_to_xy(white)
    XYZ_a = colour.Lab_to_XYZ(np.array(lab_a), xy_white) * 100.0
    XYZ_b = colour.Lab_to_XYZ(np.array(lab_b), xy_white) * 100.0
    assert float(delta_E2000(XYZ_a, XYZ_b, white)) == pytest.approx(expected, abs=1e-4)


def test_delta_E2000_rejects_nan_and_dark_white():
    with pytest.raises(InputError, match="NaN"):
        delta_E2000([np.nan, 1, 1], [1, 1, 1], [95, 100, 108])
    with pytest.raises(InputError):
        delta_E2000([1, 1, 1], [1, 1, 1], [0, 0, 0])
