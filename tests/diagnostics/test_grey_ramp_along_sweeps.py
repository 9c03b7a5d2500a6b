"""Along dense sweeps whose tone curves are not power laws, the coarse grey ramp is drawn between
its greys in the shape of each channel's own sweep (smoothed), not along the power law through two
greys.

``paper+greys`` sessions of the independent generator: a sweep point every 5 DAC a channel and a
grey every 16. Hidden colours are the peer bench's (:func:`~tests.diagnostics.peer_bench.hidden_score`).
"""

from __future__ import annotations

import numpy as np

from tests.diagnostics.independent_generator import generate_session
from tests.diagnostics.peer_bench import hidden_score
from workbench.diagnostics import diagnose
from workbench.diagnostics.authors import fit_grey_ramp_linearisation, grey_ramp_model
from workbench.diagnostics.model_choice import fit_candidate


def _scores(effects, seed):
    """(generated session, diagnosis, hidden ΔE00 of the export, of the authors' method)."""
    generated = generate_session(effects, seed=seed, plan="paper+greys")
    diagnosis = diagnose(generated.session)
    authors = fit_grey_ramp_linearisation(generated.session)
    return (generated, diagnosis,
            hidden_score(generated, diagnosis.extended, diagnosis.white, seed),
            hidden_score(generated, authors, diagnosis.white, seed))


def test_a_toe_between_the_greys_follows_the_sweeps():
    # the toe crushes DAC 8 to black and rises between the greys at 16 and 32 more steeply than
    # the power law through them (an exponent of 2.3 there): bent along power laws the grey ramp
    # scored 0.228 mean ΔE00 on hidden colours, worse than the authors' straight lines (0.201)
    _, diagnosis, exported, authors = _scores({"tone-curve-shape": "toe"}, 35004)
    assert "tone-curve-shape" in {f.effect for f in diagnosis.findings}
    assert diagnosis.model_choice.chosen == "grey-ramp", diagnosis.model_choice.reason
    assert exported < authors - 0.05


def test_power_laws_stay_between_the_greys_where_the_tone_curves_were_not_found_bent():
    # a clean display: the sweeps' shape is a power law within their noise, and the power laws
    # through the greys carry none of it
    generated, diagnosis, _, _ = _scores({}, 30003)
    assert not {f.effect for f in diagnosis.findings} & {"tone-curve-shape", "channel-interaction"}
    candidate = fit_candidate("grey-ramp", diagnosis.context, ())
    power = grey_ramp_model(diagnosis.context.fit, diagnosis.context.white, power_segments=True)
    rgb = np.random.default_rng(1).integers(0, 256, (200, 3))
    np.testing.assert_allclose(candidate.forward(rgb), power.forward(rgb), rtol=1e-12)
    # where a tone-curve shape was found the sweeps shape it, unless the channels interact: a
    # single channel's sweep then runs at another load than the grey at the same drive
    shaped = fit_candidate("grey-ramp", diagnosis.context, ("tone-curve-shape",))
    assert not np.allclose(shaped.forward(rgb), power.forward(rgb), rtol=1e-6)
    interacting = fit_candidate("grey-ramp", diagnosis.context,
                                ("tone-curve-shape", "channel-interaction"))
    np.testing.assert_allclose(interacting.forward(rgb), power.forward(rgb), rtol=1e-12)
