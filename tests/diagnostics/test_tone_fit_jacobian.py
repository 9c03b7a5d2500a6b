"""The tone test's fits take their Jacobian in closed form: it must be the shapes' derivative."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from workbench.diagnostics.detectors import _SHAPE_START, _fit_shape, _shape, _shape_derivatives


@pytest.mark.parametrize("form", sorted(_SHAPE_START))
def test_each_shapes_derivatives_are_its_central_differences(form):
    rng = np.random.default_rng(5)
    start, low, high = _SHAPE_START[form]
    drive = np.concatenate([[0.0], np.sort(rng.uniform(0.02, 1.0, 30)), [1.0]])
    for _ in range(25):
        p = np.array([rng.uniform(a, b) for a, b in zip(low, high)])
        analytic = _shape_derivatives(form, drive, p)
        assert analytic.shape == (drive.size, p.size)
        for k in range(p.size):
            step = np.zeros_like(p)
            step[k] = 1e-6
            numeric = (_shape(form, drive, p + step) - _shape(form, drive, p - step)) / 2e-6
            np.testing.assert_allclose(analytic[:, k], numeric, rtol=1e-3, atol=1e-6)


@pytest.mark.parametrize("form", sorted(_SHAPE_START))
def test_a_fit_with_the_closed_form_jacobian_reaches_the_finite_difference_fits_minimum(form):
    rng = np.random.default_rng(9)
    start, low, high = _SHAPE_START[form]
    drive = np.arange(5, 256, 20) / 255.0
    for trial in range(10):
        Y = 0.2 + 80.0 * drive ** rng.uniform(1.8, 2.8)
        if trial % 2:  # a shoulder the power law does not follow
            Y = np.where(drive > 0.7, Y[drive > 0.7].min() + 0.5 * (Y - Y[drive > 0.7].min()), Y)
        sd = 0.003 * Y + 0.01
        Y = Y + sd * rng.standard_normal(Y.size)
        _, chi2 = _fit_shape(form, drive, Y, sd, 0.2, 80.0)
        reference = least_squares(
            lambda q: (q[0] + q[1] * _shape(form, drive, q[2:]) - Y) / sd,
            x0=[0.2, 80.0, *start], bounds=([-np.inf, 0.0, *low], [np.inf, np.inf, *high]))
        assert chi2 <= 2 * reference.cost * (1 + 1e-6) + 1e-9, (trial, chi2, 2 * reference.cost)
