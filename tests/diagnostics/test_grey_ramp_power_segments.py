"""The grey-ramp candidate between sparse sweeps or coarse greys: power laws between its greys.

With a channel's sweep read at ten levels (the adaptive plan), or with greys 16 DAC apart
(``paper+greys``), a straight line between two greys is a chord of a curve that rises about as
``d^2.2``: a few per cent too bright in the shadows. With a fine grey ramp (the seed authors' plan,
a grey every 5 DAC) the candidate stays the authors' method exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.diagnostics.independent_generator import generate_session, hidden_colours
from workbench.colorimetry import delta_E2000
from workbench.diagnostics.authors import grey_ramp_model
from workbench.diagnostics.detectors import build_context
from workbench.diagnostics.model_choice import bends_between_greys, fit_candidate, has_sparse_sweep

SPARSE_LEVELS = (25, 50, 75, 100, 125, 150, 175, 200, 225, 250, 255)
"""Sweep levels kept: ten below full drive, as the adaptive plan's core reads."""


@pytest.mark.parametrize("seed", [5, 6])
def test_between_sparse_sweeps_the_grey_ramp_follows_power_laws_between_its_greys(seed):
    generated = generate_session(None, seed=seed, plan="paper+greys", noise=0.0005)
    fit = generated.session.without("validation")
    sweep = fit.mask("ramp-r", "ramp-g", "ramp-b")
    sparse = fit.subset(~sweep | np.isin(fit.rgb.max(axis=1), SPARSE_LEVELS))
    rgb = hidden_colours(300, seed)
    truth, white = generated.true_at(rgb), generated.true_at([[255, 255, 255]])[0]

    def hidden(model):
        return float(np.mean(delta_E2000(model.forward(rgb), truth, white)))

    context = build_context(sparse)
    assert has_sparse_sweep(context)
    bent = fit_candidate("grey-ramp", context)
    chords = grey_ramp_model(context.fit, context.white)
    assert len(bent.tone[0].drive_points) > 10 * len(chords.tone[0].drive_points)
    assert hidden(bent) < 0.8 * hidden(chords)
    # dense sweeps, greys 16 DAC apart: bent too
    dense = build_context(fit)
    assert not has_sparse_sweep(dense) and bends_between_greys(dense)
    assert hidden(fit_candidate("grey-ramp", dense)) < 0.8 * hidden(grey_ramp_model(dense.fit,
                                                                                   dense.white))


@pytest.mark.parametrize("seed", [5, 6])
def test_along_the_authors_fine_grey_ramp_the_candidate_is_their_method(seed):
    fit = generate_session(None, seed=seed, plan="authors-2024").session.without("validation")
    context = build_context(fit)
    assert not bends_between_greys(context)
    candidate, authors = fit_candidate("grey-ramp", context), grey_ramp_model(context.fit,
                                                                              context.white)
    for ours, theirs in zip(candidate.tone, authors.tone):
        assert ours.drive_points == theirs.drive_points
        assert ours.output_points == theirs.output_points
