"""The power-limit fit takes its Jacobian in closed form: it must be the load law's derivative,
and the fit must reach the minimum the finite-difference fit reached."""

from __future__ import annotations

import numpy as np
import pytest

import workbench.diagnostics.power_limit as power_limit
from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics.detectors import build_context
from workbench.diagnostics.power_limit import _load_law, _load_law_jacobian, fit_power_limit


def _stacked(theta, channel, drive, mix_drive):
    sweep, white, mixed = _load_law(theta, channel, drive, mix_drive)
    return np.concatenate([sweep, [white], mixed])


@pytest.mark.parametrize("seed", range(6))
def test_the_jacobian_is_the_load_laws_central_differences(seed):
    rng = np.random.default_rng(seed)
    channel = np.repeat([0, 1, 2], 20)
    drive = np.concatenate([[0.0], rng.uniform(0.01, 1.0, 58), [1.0]])
    mix_drive = rng.uniform(0.0, 1.0, (15, 3))
    mix_drive[0] = 0.5  # a grey
    theta = np.array([*rng.uniform(1.6, 3.0, 3), *rng.uniform(10, 80, 3),
                      rng.uniform(0.02, 0.3), rng.uniform(0.0, 0.6), rng.uniform(1.0, 3.0),
                      rng.uniform(-0.2, 0.2)])
    analytic = _load_law_jacobian(theta, channel, drive, mix_drive)
    assert analytic.shape == (drive.size + 1 + len(mix_drive), theta.size)
    for k in range(theta.size):
        step = np.zeros_like(theta)
        step[k] = 1e-6 * max(1.0, abs(theta[k]))
        numeric = (_stacked(theta + step, channel, drive, mix_drive)
                   - _stacked(theta - step, channel, drive, mix_drive)) / (2 * step[k])
        np.testing.assert_allclose(analytic[:, k], numeric, rtol=1e-4, atol=1e-5 * 80,
                                   err_msg=f"parameter {k}")


@pytest.mark.parametrize("form,seed", [("power-limit-quadratic", 30400), ("knee", 30401),
                                       ("backlight", 30402)])
def test_the_fit_reaches_the_finite_difference_fits_minimum(form, seed, monkeypatch):
    generated = generate_session({"channel-interaction": form}, seed=seed, plan="paper+greys")
    context = build_context(generated.session.without("validation"))
    closed = fit_power_limit(context, mixtures=True)
    solve = power_limit.least_squares

    def finite_differences(fun, x0, jac=None, **kw):
        return solve(fun, x0, **kw)

    monkeypatch.setattr(power_limit, "least_squares", finite_differences)
    numeric = fit_power_limit(context, mixtures=True)
    assert closed.chi2 <= numeric.chi2 * (1 + 1e-6) + 1e-9
    np.testing.assert_allclose([closed.loss, *closed.gamma], [numeric.loss, *numeric.gamma],
                               atol=1e-3)
