"""A power limit that loads the panel by current, not by light: the load's channel weights fitted.

The independent generator's power limits weigh each channel in the load by its share of the
white's luminance, as the workbench's power-limit fit did: a test that shares the model's
assumption proves little. An OLED limits the current it draws, and its blue subpixels give a
tenth of the candela per ampere its green ones do, so blue weighs several times its luminance
share in the load. The generator's ``current-load`` probe draws such a panel (efficiencies red
20–40, green 50–100, blue 5–12 cd/A); the truth is its own display.
"""

import numpy as np
import pytest

import workbench.diagnostics.power_limit as power_limit
from tests.diagnostics.follow_up_bench import session_outcome
from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics.detectors import build_context
from workbench.diagnostics.power_limit import fit_power_limit

FORMS = ("power-limit-quadratic", "knee", "power-limit")
SEEDS = (77000, 77001, 77002)


def _fit(form, seed, probe):
    generated = generate_session({"channel-interaction": form}, seed=seed, plan="paper+greys",
                                 probe=probe)
    return generated, fit_power_limit(build_context(generated.session), mixtures=True)


@pytest.mark.parametrize("form", FORMS)
def test_a_load_weighed_by_light_keeps_the_luminance_law(form):
    for seed in SEEDS:
        generated, fit = _fit(form, seed, None)
        assert fit.load_weights is None, (seed, fit.load_weights)
        assert abs(fit.loss - generated.display.interaction[1]) < 0.01


@pytest.mark.parametrize("form", FORMS)
def test_a_load_weighed_by_current_gets_its_weights_fitted(form):
    for seed in SEEDS:
        generated, fit = _fit(form, seed, "current-load")
        truth = generated.display.load_weights
        assert fit.load_weights is not None, seed
        weights = np.asarray(fit.load_weights)
        assert np.isclose(weights.sum(), 1.0) and np.all(weights > 0)
        # nearer the panel's weights than the light's shares are (a knee shows them only past it)
        shares = generated.display.shares
        assert np.linalg.norm(weights - truth) < 0.6 * np.linalg.norm(shares - truth), (
            seed, weights, truth)
        # blue weighs several times its share of the light, as the panel's current says
        assert weights[2] > 2.5 * generated.display.shares[2]
        assert abs(fit.loss - generated.display.interaction[1]) < 0.01
        assert np.allclose(fit.weights, weights)  # what the exported model's load reads


def test_after_the_follow_up_a_current_loaded_knee_is_exported_right(monkeypatch):
    """A knee on the paper plan, followed up: with the weights fitted the power-limit model takes
    the held-out gain past 30 %; held to the luminance law, the same model dims the wrong colours
    and loses to the paper's model."""
    fitted = session_outcome("knee", 76004, strict=True, probe="current-load")
    assert fitted.model_after == "power-limit"
    assert fitted.hidden_gain_after >= 0.3, fitted.hidden_gain_after
    monkeypatch.setattr(power_limit, "_free_weights_fit", lambda *args: None)
    luminance = session_outcome("knee", 76004, strict=True, probe="current-load")
    assert luminance.hidden_gain_after < 0.3, luminance.hidden_gain_after
    assert fitted.hidden_exported_after < 0.5 * luminance.hidden_exported_after
