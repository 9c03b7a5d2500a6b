"""The independent generator's probes: a display or a noise none of its forms draws.

A probe (``generate_session(probe=…)``) must change only what it says, from a stream of its own:
the generator's sessions without one stay bit for bit as they were, and a probe's session keeps
its seed's display and effects. The diagnosis is then asked to hold on it as on the generator's
own sessions: a clean display gets no finding and a profile no worse than the seed authors'
method, and an injected cause is still named first. ``bench peers --probe NAME`` measures the
rates (docs/diagnostics/peers.md).
"""

import numpy as np
import pytest

from tests.diagnostics.independent_generator import (
    BT2020_PRIMARIES_XY,
    PROBES,
    generate_session,
)
from tests.diagnostics.peer_bench import WORSE_BY, hidden_score

SEED = 84000


def _bright(generated, share=0.1):
    """Rows lit above ``share`` of the white's Y."""
    return generated.true_XYZ[:, 1] > share * generated.display.white_Y


def test_a_session_without_a_probe_is_unchanged():
    # the probes draw from streams of their own: nothing the generator drew before moves
    plain = generate_session({"tone-curve-shape": "toe"}, seed=SEED, plan="authors-2024")
    for probe in ("chromaticity-noise", "correlated-noise"):
        probed = generate_session({"tone-curve-shape": "toe"}, seed=SEED, plan="authors-2024",
                                  probe=probe)
        assert np.array_equal(plain.true_XYZ, probed.true_XYZ)
        assert probed.effects == plain.effects and probed.noise == plain.noise
        assert not np.array_equal(plain.session.XYZ, probed.session.XYZ)
        assert probed.session.metadata["probe"] == probe
    assert "probe" not in plain.session.metadata


def test_the_command_line_lists_the_generators_probes():
    # `bench peers --help` names them without importing the tests
    from workbench.cli.bench import PEER_PROBES

    assert PEER_PROBES == tuple(PROBES)


def test_an_unknown_probe_is_named_with_the_known_ones():
    with pytest.raises(ValueError, match="no probe 'oled'.*wide-gamut"):
        generate_session(seed=SEED, probe="oled")


@pytest.mark.parametrize("seed", range(SEED, SEED + 4))
def test_the_wide_gamut_probe_draws_bt2020_primaries(seed):
    generated = generate_session(seed=seed, plan="paper", probe="wide-gamut")
    display = generated.display
    assert np.all(np.abs(display.primaries_xy - BT2020_PRIMARIES_XY) <= 0.01)
    assert 20.0 <= display.white_Y <= 400.0 and np.all((1.8 <= display.gammas)
                                                       & (display.gammas <= 2.8))
    # the effect-free display is the same panel: a clean session is the paper's model of it
    assert np.allclose(generated.effect_free_XYZ, generated.true_XYZ)
    white = generated.true_at([[255, 255, 255]])[0]
    assert np.allclose(white[:2] / white.sum(), display.white_xy)


def test_the_chromaticity_noise_probe_reads_xy_to_the_datasheet_repeatability():
    generated = generate_session(seed=SEED, plan="authors-2024", probe="chromaticity-noise")
    bright = _bright(generated, 0.5)  # the floor's share of xy small beside 0.0002
    measured, truth = generated.session.XYZ[bright], generated.true_XYZ[bright]
    xy_error = measured[:, :2] / measured.sum(axis=1, keepdims=True) - \
        truth[:, :2] / truth.sum(axis=1, keepdims=True)
    assert 0.00015 < np.std(xy_error) < 0.00026
    # luminance read to a of itself, as the generator's gain noise
    relative = measured[:, 1] / truth[:, 1] - 1
    assert 0.7 * generated.noise < np.std(relative) < 1.3 * generated.noise


def test_the_correlated_noise_probe_carries_its_gain_from_reading_to_reading():
    plain = generate_session(seed=SEED, plan="authors-2024")
    probed = generate_session(seed=SEED, plan="authors-2024", probe="correlated-noise")
    bright = _bright(probed)
    added = (probed.session.XYZ[bright, 1] - plain.session.XYZ[bright, 1]) / \
        probed.true_XYZ[bright, 1]
    assert np.std(added) == pytest.approx(probed.noise, rel=0.5)
    # the added gain alone: consecutive bright readings move together
    assert np.corrcoef(added[:-1], added[1:])[0, 1] > 0.6


@pytest.mark.parametrize("probe", sorted(PROBES))
def test_a_clean_display_under_a_probe_gets_no_finding_and_no_worse_profile(probe):
    from workbench.diagnostics import diagnose
    from workbench.diagnostics.authors import fit_grey_ramp_linearisation

    generated = generate_session(seed=SEED, plan="authors-2024", probe=probe)
    diagnosis = diagnose(generated.session)
    assert not diagnosis.findings, [f.effect for f in diagnosis.findings]
    ours = hidden_score(generated, diagnosis.extended, diagnosis.white, SEED)
    authors = hidden_score(generated, fit_grey_ramp_linearisation(generated.session),
                           diagnosis.white, SEED)
    assert ours <= authors + WORSE_BY, (ours, authors)


def test_a_power_limit_on_a_wide_gamut_panel_is_named_first():
    from workbench.diagnostics import diagnose

    generated = generate_session({"channel-interaction": "power-limit-quadratic"}, seed=SEED,
                                 plan="paper", probe="wide-gamut")
    diagnosis = diagnose(generated.session)
    assert [f.effect for f in diagnosis.findings][0] == "channel-interaction"
    assert diagnosis.model_choice.chosen == "power-limit"
