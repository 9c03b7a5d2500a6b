"""The spectral basis: accuracy against the full-band path on reflectances it never saw."""

import numpy as np
import pytest

from workbench.colorimetry import WORKING_WAVELENGTHS, delta_E2000
from workbench.errors import InputError
from workbench.hyperspectral import (
    ACCURACY_SOURCES,
    BASIS_SOURCES,
    PAPER_CUBE_WAVELENGTHS,
    XYZ_band_weights,
    basis_accuracy,
    encode_cube,
    fit_spectral_basis,
    resampling_matrix,
)
from workbench.illuminants import get_illuminant
from workbench.samples import ces99, colorchecker

WAVELENGTHS = PAPER_CUBE_WAVELENGTHS


def _at_cube_bands(reflectances):
    return reflectances @ resampling_matrix(WORKING_WAVELENGTHS, WAVELENGTHS).T


def _mixtures(reflectances, count, seed):
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, len(reflectances), (count, 3))
    shares = rng.dirichlet([1.0, 1.0, 1.0], count)
    return np.einsum("nk,nkb->nb", shares, reflectances[picks])


@pytest.fixture(scope="module")
def ces_basis():
    """Fitted on the 99 CIE 2017 samples and their mixtures only."""
    ces = _at_cube_bands(ces99().reflectances)
    return fit_spectral_basis(np.vstack([ces, _mixtures(ces, 2000, seed=1)]), WAVELENGTHS)


def test_basis_matches_full_band_on_other_materials(ces_basis):
    # The ColorChecker's pigments are not among the CIE 2017 samples the basis was fitted on.
    cc = _at_cube_bands(colorchecker().reflectances)
    unseen = np.vstack([cc, _mixtures(cc, 500, seed=2)])
    accuracy = basis_accuracy(ces_basis, unseen, ACCURACY_SOURCES)
    assert set(accuracy.max_dE00) == set(ACCURACY_SOURCES)
    for source, value in accuracy.max_dE00.items():
        assert value <= 0.5, (source, value)
    assert accuracy.samples == len(unseen)


def test_accuracy_is_the_full_band_comparison_it_claims(ces_basis):
    cc = _at_cube_bands(colorchecker().reflectances)
    W = XYZ_band_weights(get_illuminant("cie-a").sd, WAVELENGTHS)
    approx = ces_basis.reconstruct(ces_basis.coefficients(cc)) @ W
    expected = delta_E2000(approx, cc @ W, W.sum(axis=0)).max()
    assert basis_accuracy(ces_basis, cc, ["cie-a"]).max_dE00["cie-a"] == pytest.approx(expected)


def test_K_follows_the_target(ces_basis):
    assert ces_basis.meets_target and ces_basis.held_out.worst_dE00 <= ces_basis.target_max_dE00
    ces = _at_cube_bands(ces99().reflectances)
    loose = fit_spectral_basis(np.vstack([ces, _mixtures(ces, 2000, seed=1)]), WAVELENGTHS,
                               target_max_dE00=3.0)
    assert loose.components < ces_basis.components
    assert loose.held_out.worst_dE00 <= 3.0


def test_encoder_and_decoder_are_inverse_on_the_kept_subspace(ces_basis):
    np.testing.assert_allclose(ces_basis.vectors @ ces_basis.projection,
                               np.eye(ces_basis.components), atol=1e-9)


def test_imposed_K_and_bad_requests(ces_basis):
    ces = _at_cube_bands(ces99().reflectances)
    basis = fit_spectral_basis(ces, WAVELENGTHS, components=5)
    assert basis.components == 5 and np.isnan(basis.target_max_dE00) and basis.meets_target
    with pytest.raises(InputError, match="choose 1.."):
        fit_spectral_basis(ces, WAVELENGTHS, components=500)
    with pytest.raises(InputError, match="NaN"):
        fit_spectral_basis(np.full((10, WAVELENGTHS.size), np.nan), WAVELENGTHS)
    with pytest.raises(InputError, match="bands"):
        ces_basis.coefficients(np.ones(7))


def test_cube_coefficients_are_float16_planes(small_cube):
    basis = fit_spectral_basis(small_cube.texels(), small_cube.wavelengths)
    texture = encode_cube(small_cube, basis)
    assert texture.coefficients.dtype == np.float16
    assert texture.coefficients.shape == (basis.components, small_cube.height, small_cube.width)
    expected = basis.coefficients(small_cube.data[7, 9])
    np.testing.assert_allclose(texture.coefficients[:, 7, 9].astype(float), expected.astype(float),
                               rtol=2e-3, atol=2e-3)


def test_too_few_samples_to_hold_any_out_is_an_error():
    from workbench.hyperspectral.basis import split_held_out

    train, held = split_held_out(5)
    assert len(held) == 1 and len(train) == 4 and not set(train) & set(held)
    for count in (0, 1, 4):
        with pytest.raises(InputError, match="at least 5"):
            split_held_out(count)
    ces = _at_cube_bands(ces99().reflectances)
    with pytest.raises(InputError, match="held-out"):
        fit_spectral_basis(ces[:4], WAVELENGTHS)
    basis = fit_spectral_basis(ces[:4], WAVELENGTHS, held_out=ces[4:10], components=2)
    assert basis.components == 2 and basis.held_out.samples == 6


def test_benchmark_sets_are_disjoint_by_material():
    from workbench.hyperspectral.materials import (
        TEST_MATERIALS,
        TRAINING_MATERIALS,
        VALIDATION_MATERIALS,
        held_out_material_sets,
        material_reflectances,
    )

    assert len({TRAINING_MATERIALS, VALIDATION_MATERIALS, *TEST_MATERIALS}) == 4
    seen = np.vstack([material_reflectances(TRAINING_MATERIALS, WAVELENGTHS),
                      material_reflectances(VALIDATION_MATERIALS, WAVELENGTHS)])
    for name in TEST_MATERIALS:
        for spectrum in material_reflectances(name, WAVELENGTHS):
            assert np.abs(seen - spectrum).max(axis=1).min() > 0.01, name
    training, validation, test = held_out_material_sets(WAVELENGTHS)
    assert set(test) == set(TEST_MATERIALS)
    # Every training texel is a convex mixture of the training materials: inside their range.
    training_spectra = material_reflectances(TRAINING_MATERIALS, WAVELENGTHS)
    assert np.all(training >= training_spectra.min(axis=0) - 1e-6)
    assert np.all(training <= training_spectra.max(axis=0) + 1e-6)
    assert len(validation) > len(material_reflectances(VALIDATION_MATERIALS, WAVELENGTHS))


def test_basis_accuracy_held_out_by_material():
    """The split by material: fitted on CIE 2017 samples, K chosen on the CIE 13.3 samples,
    accurate on the ColorChecker and the NIST CQS samples, which neither step saw."""
    from workbench.hyperspectral.materials import (
        HELD_OUT_TARGET_MAX_DE00,
        held_out_material_sets,
    )

    training, validation, test = held_out_material_sets(WAVELENGTHS)
    basis = fit_spectral_basis(training, WAVELENGTHS, held_out=validation,
                               target_max_dE00=HELD_OUT_TARGET_MAX_DE00,
                               sources=tuple(dict.fromkeys(BASIS_SOURCES + ACCURACY_SOURCES)))
    assert basis.meets_target
    for name, reflectances in test.items():
        accuracy = basis_accuracy(basis, reflectances, ACCURACY_SOURCES)
        assert accuracy.samples == len(reflectances)
        for source, value in accuracy.max_dE00.items():
            assert value <= 0.5, (name, source, value)
