"""Every model a diagnosis cross-validates is scored on the same folds, built once per session: the
errors are those of folds built afresh, and nothing outlives the session."""

from __future__ import annotations

import gc

import numpy as np

import workbench.diagnostics.cross_validation as cross_validation
from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics.cross_validation import cross_validated_errors
from workbench.diagnostics.detectors import build_context


def _context(seed=30500):
    generated = generate_session({"temporal-drift": "warm-up"}, seed=seed, plan="paper+greys")
    return build_context(generated.session.without("validation"))


def test_a_reused_fold_scores_as_a_fresh_one():
    context = _context()
    candidates = [None, [], ["temporal-drift"], ["temporal-drift", "tone-curve-shape"]]
    reused = [cross_validated_errors(context, effects) for effects in candidates]
    # each fold built twice (with the drift correction and without), whatever the candidates
    fold = cross_validation.fold_of_rows(context)
    folds = np.unique(fold[fold >= 0]).size
    built = cross_validation._FOLDS_BUILT[context.raw]
    assert len(built) == 2 * folds and all(len(entries) == 1 for entries in built.values())
    fresh = []
    for effects in candidates:
        cross_validation._FOLDS_BUILT.clear()
        fresh.append(cross_validated_errors(context, effects))
    for (a, groups_a), (b, groups_b) in zip(reused, fresh):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(groups_a, groups_b)


def test_a_fold_built_with_another_noise_model_is_not_reused():
    context = _context()
    cross_validated_errors(context, [])
    other = build_context(context.raw, drift_found=context.drift_found,
                          noise=type(context.noise)(**{**vars(context.noise),
                                                        "gain_sd": 2 * context.noise.gain_sd}))
    cross_validated_errors(other, [])
    built = cross_validation._FOLDS_BUILT[context.raw]
    assert all(len(entries) == 2 for entries in built.values())


def test_the_folds_go_with_their_session():
    context = _context(30501)
    cross_validated_errors(context, [])
    session = context.raw
    assert session in cross_validation._FOLDS_BUILT
    count = len(cross_validation._FOLDS_BUILT)
    del context, session
    gc.collect()
    assert len(cross_validation._FOLDS_BUILT) < count
