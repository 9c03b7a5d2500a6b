"""A full-drive primary read far off its own sweep is the reading's, not the panel's.

The additivity test reads each primary once or a few times against the white read ten times or
more. Instrument readings have heavier tails than a Gaussian (the independent generator draws
its gain noise from a Student t with 6 degrees of freedom), and one primary read several
standard deviations off names a channel interaction that its own sweep and the greys deny. The
test is therefore also made with each primary that stands off the log-log extrapolation of its
sweep's top levels (:func:`~workbench.diagnostics.detectors.primaries_off_their_sweeps`) read
from them instead, and the least favourable p-value is kept.
"""

from dataclasses import replace

import numpy as np

from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics import diagnose
from workbench.diagnostics.detectors import (PRIMARY_OFF_SWEEP_Z, build_context,
                                             primaries_off_their_sweeps, white_against_sum)


def _listed(context):
    _, summed, covariance, _ = white_against_sum(context)
    return primaries_off_their_sweeps(context, summed, covariance)


def test_clean_primaries_stand_on_their_sweeps():
    for seed in range(6):
        context = build_context(generate_session(None, seed=seed, plan="authors-2024")
                                .session.without("validation"))
        assert _listed(context) == []


def test_a_primary_read_three_percent_low_is_listed_with_its_sweep_estimate():
    session = generate_session(None, seed=1, noise=0.002, plan="authors-2024").session
    full_blue = np.flatnonzero(np.all(session.rgb == [0, 0, 255], axis=1))
    XYZ = session.XYZ.copy()
    XYZ[full_blue] *= 0.97
    context = build_context(replace(session, XYZ=XYZ).without("validation"))
    listed = _listed(context)
    assert [entry[0] for entry in listed] == [2]
    _, departure, z, summed, _ = listed[0]
    assert -0.035 < departure < -0.025 and z > PRIMARY_OFF_SWEEP_Z
    # the sum with the blue read from its sweep is within 1 % of the sum as it was measured
    truth = build_context(session.without("validation"))
    expected = sum(s.full_XYZ for s in truth.sweeps)
    assert np.all(np.abs(summed / expected - 1) < 0.01)


def test_a_blue_primary_read_far_off_its_sweep_names_no_interaction():
    """Peer display 72007 on the seed authors' plan: its one blue full-drive reading is 2.3 % low
    (a t tail draw at 0.45 % noise), the white's Z 102 % of R+G+B (χ² 20 on 3 dof), the greys
    the sum of their channels' sweeps (p 0.37): a channel interaction had been named."""
    generated = generate_session({"black-offset": "bluish"}, seed=72007, plan="authors-2024")
    diagnosis = diagnose(generated.session)
    assert [f.effect for f in diagnosis.findings] == ["black-offset"]
    interaction = next(r for r in diagnosis.results if r.effect == "channel-interaction")
    assert "blue primary read from its own sweep's top levels" in interaction.evidence


def test_interactions_are_still_named():
    for form in ("power-limit", "knee", "backlight"):
        diagnosis = diagnose(generate_session({"channel-interaction": form}, seed=3,
                                              plan="authors-2024").session)
        assert "channel-interaction" in [f.effect for f in diagnosis.findings], form
