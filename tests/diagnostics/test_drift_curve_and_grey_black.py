"""The drift correction's curve, and the grey-ramp model's black.

The drift curve: ±σ jitter of the references about a trend is averaged out, and a step stays a
step (a smoother alone blurs it across the references beside it). Its reference state is read from
every reference of the settled end, not from the last two alone, and only from those that are
settled. The grey-ramp model: a black read a
little below zero (noise about none) is taken as zero, and the greys are read against that same
black, so the model still reproduces the greys it was built from.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tests.diagnostics.independent_generator import PAIRED_FORMS, generate_session, hidden_colours
from workbench.colorimetry import delta_E2000
from workbench.diagnostics.authors import fit_grey_ramp_linearisation, grey_ramp_model
from workbench.diagnostics.evidence import (DriftCorrection, partial_greys, settled_reference,
                                           settled_scatter)


def test_jitter_about_a_decline_is_averaged_out():
    times = np.arange(12.0)
    truth = 1.0 - 0.004 * times  # 4.4 % over the session, 11 σ
    sd = 0.004
    rms = []
    for seed in range(20):
        gains = truth * (1.0 + sd * np.random.default_rng(seed).standard_normal(times.size))
        curve = DriftCorrection(times, gains, gains).smoothed_to_noise(np.full(times.size, sd))
        # the curve's shape (the reference state it is scaled to is tested below)
        scale = gains[0] / curve.gains[0]
        rms.append(np.sqrt(np.mean((curve.gain(times) * scale - truth) ** 2)))
    # a straight line through 12 references is known to about 0.4 σ; one reference to 1 σ
    assert np.mean(rms) < 0.6 * sd


def test_a_fast_warm_up_does_not_hold_the_settled_references_to_their_noise(monkeypatch):
    # a warm-up 6.5 % up between the first two references and 1 % more after them, then
    # settled (as the peer bench's "warm-up beside sweeps" does): one smoothing strength for
    # the whole curve must follow the bend at the second reference and so copies the noise of
    # every reference after it (about 1 σ); a free kink at the bend leaves the rest smooth
    from workbench.diagnostics import evidence

    times = np.array([48.0, 630, 730, 1030, 1130, 1840, 1990, 2270, 2370, 2390, 2500, 2620])
    truth = 1.0 - 0.08 * np.exp(-times / 300.0)
    sd = 0.002

    def settled_rms():
        rms = []
        for seed in range(40):
            noise = np.random.default_rng(seed).standard_t(6, times.size) / np.sqrt(1.5)
            gains = truth * (1.0 + sd * noise)
            curve = DriftCorrection(times, gains, gains).smoothed_to_noise(
                np.full(times.size, sd))
            scale = float(np.mean(truth[-4:] / curve.gain(times[-4:])))  # the curve's shape
            rms.append(np.sqrt(np.mean((curve.gain(times[1:]) * scale - truth[1:]) ** 2)))
        return float(np.mean(rms))

    kinked = settled_rms()
    monkeypatch.setattr(evidence, "MIN_KINK_REFERENCES", times.size + 1)
    plain = settled_rms()
    assert kinked < 0.85 * plain and kinked < 0.9 * sd, (kinked, plain)


@pytest.mark.parametrize("kink", [None, 3])
def test_the_smoothers_at_every_strength_are_the_whittaker_solves(kink):
    # every strength at once through one eigendecomposition: the same curve, effective degrees
    # of freedom and hat as solving (W + s P) c = W g at each strength
    from workbench.diagnostics.evidence import SMOOTHING_STRENGTHS, _smoother_path

    rng = np.random.default_rng(7)
    n = 14
    times = np.sort(rng.uniform(0, 3000, n))
    sd = rng.uniform(0.002, 0.006, n)  # unequal noise: the basis is weighted, not plain
    gains = (1 - 0.05 / (1 + (times / 400) ** 2)) * (1 + sd * rng.standard_t(5, n))
    rows = np.diff(np.eye(n), 2, axis=0)
    if kink is not None:
        rows = np.delete(rows, kink - 1, axis=0)
    weight = np.diag(sd ** -2.0)
    scores, hats = [], []
    for strength in SMOOTHING_STRENGTHS:
        hat = np.linalg.solve(weight + strength / np.mean(sd) ** 2 * rows.T @ rows, weight)
        curve = hat @ gains
        scores.append(np.sum(((curve - gains) / sd) ** 2) + 2 * (np.trace(hat) + 1.5))
        hats.append(hat)
    pick = int(np.argmin(scores))
    score, curve, hat = _smoother_path(gains, sd, rows, 1.5)
    assert score == pytest.approx(scores[pick], rel=1e-9)
    np.testing.assert_allclose(hat, hats[pick], atol=1e-9)
    np.testing.assert_allclose(curve, hats[pick] @ gains, atol=1e-12)
    assert 0 < pick < len(SMOOTHING_STRENGTHS) - 1  # a strength inside the grid was chosen


def test_a_step_stays_a_step():
    times = np.arange(12.0)
    truth = np.where(times < 5, 1.03, 1.0)
    sd = 0.003
    worst = []
    for seed in range(20):
        gains = truth * (1.0 + sd * np.random.default_rng(100 + seed).standard_normal(times.size))
        curve = DriftCorrection(times, gains, gains).smoothed_to_noise(np.full(times.size, sd))
        scale = gains[0] / curve.gains[0]
        worst.append(np.max(np.abs(curve.gain(times) * scale - truth)))
    # the references beside the step are not blurred toward each other (that is 5 σ). The curve
    # is scored against the settled references' scatter where that is larger than their noise
    # (settled_scatter): on one draw of the twenty (scatter 1.14 times the noise, by chance) the
    # smoother that wins there bends across the step a little more, 3.1 σ off beside it (2.9 σ
    # scored against the noise as stated)
    assert np.median(worst) < 1.5 * sd and np.max(worst) < 3.5 * sd


def _exported_and_authors(effects: dict, seed: int, plan: str) -> tuple[float, float]:
    """Mean ΔE00 on the peer bench's hidden colours of one generated session: the exported
    profile's and the seed authors' method's, fitted on the same rows."""
    from tests.diagnostics.peer_bench import hidden_score
    from workbench.diagnostics import diagnose

    generated = generate_session(effects, seed=seed, plan=plan)
    diagnosis = diagnose(generated.session)
    authors = fit_grey_ramp_linearisation(generated.session)
    return (hidden_score(generated, diagnosis.extended, diagnosis.white, seed),
            hidden_score(generated, authors, diagnosis.white, seed))


def _settled_after_a_step(seed: int, spread: float, sd: float):
    """A 2.6 % step between the fifth and sixth of eleven references (as peer seed 31004 has it),
    heavy-tailed noise ``spread`` times ``sd``: ``(times, truth, gains)``."""
    times = np.array([34.0, 452, 557, 834, 938, 1527, 1720, 1864, 1968, 2074, 2159])
    truth = np.where(times < 1200, 1.026, 1.0)
    noise = np.random.default_rng(300 + seed).standard_t(6, times.size) / np.sqrt(1.5)
    return times, truth, truth * (1.0 + spread * sd * noise)


def test_the_settled_references_scale_their_noise_where_they_scatter_more():
    sd = np.full(11, 0.003)
    as_stated = [settled_scatter(*_settled_after_a_step(seed, 1.0, 0.003)[::2], sd)
                 for seed in range(60)]
    wider = [settled_scatter(*_settled_after_a_step(seed, 1.6, 0.003)[::2], sd)
             for seed in range(60)]
    assert min(as_stated) == 1.0 and min(wider) == 1.0  # never below the noise model
    # references as noisy as stated: mostly no scale (mean 1.03); 1.6 times that: a scale read
    # low (median 1.18), since the steadiness gate turns a run that scatters most away for a
    # shorter one, but above 1
    assert np.median(as_stated) == 1.0 and np.mean(as_stated) < 1.08
    assert np.median(wider) > 1.12 and np.mean(wider) > 1.18
    # two settled references say nothing of their own scatter
    times, _, gains = _settled_after_a_step(0, 3.0, 0.003)
    assert settled_scatter(times[:7], gains[:7], sd[:7]) == 1.0


def test_two_references_read_seconds_apart_scale_the_noise_by_their_difference():
    # peer seed 49000's whites on the authors' plan (a warm-up, settled by the greys): the one at
    # 2501 s reads 0.9 % above the one 16 s after it, 4.4 σ; the settled run is the last three
    times = np.array([48.0, 602, 708, 1027, 1131, 1910, 2105, 2397, 2501, 2517, 2622, 2735])
    gains = np.array([0.9602, 0.9829, 0.9802, 0.9910, 0.9916, 0.9949, 0.9989, 1.0025, 1.0080,
                      0.9987, 0.9986, 0.9984])
    sd = np.full(times.size, 0.0021)
    # the pair's χ² (9.8 on one degree of freedom) beside the run's (0.0 on two): √(9.8 / 3)
    assert settled_scatter(times, gains, sd) == pytest.approx(1.81, abs=0.01)
    # the same reading 67 s before the next is no pair (the median gap is 208 s), and the run of
    # three scatters less than its noise: no scale
    apart = times.copy()
    apart[8] = 2450.0
    assert settled_scatter(apart, gains, sd) == 1.0
    # a closing pair inside the settled run is read with the run, not a second time
    closing = np.append(times, 2738.0), np.append(gains, 0.9990), np.full(times.size + 1, 0.0021)
    later = closing[0].copy()
    later[-1] = 2850.0
    assert settled_scatter(*closing) == pytest.approx(settled_scatter(later, *closing[1:]))


@pytest.mark.parametrize("form, seed, margin", [("warm-up beside sweeps", 49000, -0.02),
                                                ("decline", 47001, 0.01)])
def test_a_grey_ramp_is_not_held_to_one_white_read_off_beside_another(form, seed, margin):
    # held-out peer sessions on the authors' plan. 49000: a warm-up settled by the time the greys
    # were measured, a white near the end of the grey ramp 0.9 % above the white 16 s after it;
    # the curve followed it and put the greys 0.5 % above the settled state: 0.127 mean ΔE00 on
    # hidden colours against the authors' 0.086, now 0.056. 47001: a decline, whites in pairs
    # 16 s apart up to 1.2 % apart at 0.5 % noise: 0.239 against 0.209, now 0.207
    effects = PAIRED_FORMS.get(form) or {"temporal-drift": form}
    ours, authors = _exported_and_authors(effects, seed, "authors-2024")
    assert ours <= authors + margin, (ours, authors)


def test_a_noise_read_low_does_not_let_the_curve_follow_the_settled_references():
    # the noise model reads 0.33 % where the references scatter 1.6 times that (peer seed 31004:
    # its estimate from the sweeps has an error of its own, the references' noise heavy tails):
    # scored against that noise the curve follows the references after the step (RMS from the
    # settled state 0.94 σ on average, 1.02 σ median over these 60 draws); against the settled
    # run's scatter it is mostly a step with flat levels (0.66 σ, 0.34 σ)
    sd = 0.0033
    rms = []
    for seed in range(60):
        times, truth, gains = _settled_after_a_step(seed, 1.6, sd)
        curve = DriftCorrection(times, gains, gains).smoothed_to_noise(np.full(times.size, sd))
        after = times > 1200
        rms.append(np.sqrt(np.mean((curve.gain(times[after]) - truth[after]) ** 2)))
    assert np.mean(rms) < 0.8 * sd and np.median(rms) < 0.6 * sd


def test_a_grey_ramp_beside_a_step_is_not_held_to_the_settled_references_noise():
    # held-out peer session 31004 (`paper+greys`, a bluish black beside a 2.6 % step at 0.47 %
    # noise that the noise model reads as 0.33 %): the six whites after the step scatter −0.5 to
    # +1.0 %; the curve followed them and put the greys, measured at the settled state, 0.7 %
    # above it: 0.204 mean ΔE00 on hidden colours, the authors' method 0.183. Now 0.113
    ours, authors = _exported_and_authors(PAIRED_FORMS["bluish + step"], 31004, "paper+greys")
    assert ours <= authors - 0.03, (ours, authors)


def test_the_reference_state_is_read_from_every_settled_reference():
    # a warm-up that settles halfway: the settled half's mean is known to 1/√6 of one reference
    times = np.arange(12.0) * 200.0
    truth = 1.0 - 0.05 * np.exp(-times / 150.0)
    sd = 0.003
    settled, last_two = [], []
    for seed in range(40):
        gains = truth * (1.0 + sd * np.random.default_rng(200 + seed).standard_normal(times.size))
        settled.append(settled_reference(times, gains, np.full(times.size, sd)) - truth[-1])
        last_two.append(gains[-2:].mean() - truth[-1])
    assert np.sqrt(np.mean(np.square(settled))) < 0.7 * np.sqrt(np.mean(np.square(last_two)))
    # and the correction describes the display in that state: the last reference reads about 1
    gains = truth * (1.0 + sd * np.random.default_rng(7).standard_normal(times.size))
    curve = DriftCorrection(times, gains, gains).smoothed_to_noise(np.full(times.size, sd))
    assert abs(curve.gains[-1] * settled_reference(times, gains, np.full(times.size, sd))
               / gains[-1] - 1.0) < 1e-12


def test_one_reading_off_among_the_last_three_does_not_hide_the_settled_run():
    # settled from the fifth reference on; the third last reads 2.6 σ low, the last two 1.6 σ high
    # (a heavy-tailed instrument does that now and then): the last three alone are not steady
    # (χ² 11.8 on 2 dof), every longer run is, and the state is read from the whole settled run
    times = np.arange(12.0) * 200.0
    sd = 0.003
    gains = np.concatenate([1.0 - np.array([0.04, 0.02, 0.01, 0.005]), np.ones(8)])
    gains[-3] -= 2.6 * sd
    gains[-2:] += 1.6 * sd
    reference = settled_reference(times, gains, np.full(times.size, sd))
    assert abs(reference - 1.0) < 0.3 * sd
    assert abs(gains[-2:].mean() - 1.0) > 1.5 * sd  # what the last two alone would say
    # and over Student-t readings (5 dof) about a warm-up that settles halfway, reading past a
    # run that fails does not trade the settled state for outliers: the settled runs beat the
    # last two (0.67 of their RMS error; 0.68 when the first run that failed ended the search)
    truth = 1.0 - 0.05 * np.exp(-times / 150.0)
    settled, last_two = [], []
    for seed in range(60):
        noise = np.random.default_rng(500 + seed).standard_t(5, times.size) * sd * np.sqrt(0.6)
        gains = truth * (1.0 + noise)
        settled.append(settled_reference(times, gains, np.full(times.size, sd)) - truth[-1])
        last_two.append(gains[-2:].mean() - truth[-1])
    assert np.sqrt(np.mean(np.square(settled))) < 0.75 * np.sqrt(np.mean(np.square(last_two)))


def test_a_display_still_changing_at_the_end_keeps_the_last_two():
    # a decline to the last reference, 10 σ a reference apart: no run of three is steady
    times = np.arange(10.0)
    sd = 0.001
    gains = 1.0 - 0.01 * times
    assert settled_reference(times, gains, np.full(times.size, sd)) == pytest.approx(
        gains[-2:].mean())
    # after a step of 20 σ, only the references after it are the settled state
    references = np.array([
        settled_reference(times, np.where(times < 4, 1.02, 1.0)
                          + sd * np.random.default_rng(300 + seed).standard_normal(10),
                          np.full(times.size, sd)) for seed in range(40)])
    assert np.max(np.abs(references - 1.0)) < 3 * sd
    assert np.sqrt(np.mean((references - 1.0) ** 2)) < 0.8 * sd


def test_the_grey_ramp_model_reads_the_greys_against_the_black_it_adds_back():
    # the display of peer session 30006 (a warm-up beside the sweeps, 0.16 % noise) held steady:
    # the rows are read as measured, and with a warm-up in them the greys, measured last, stand
    # above the mean of the whites that the ramp's top is
    generated = generate_session({}, seed=30006, noise=0.0016, plan="authors-2024")
    session = generated.session
    black = np.all(session.rgb == 0, axis=1)
    # every black read well below zero in Z: noise about none, as a CS-2000 can read it
    session = replace(session, XYZ=np.where(black[:, None], session.XYZ - [0, 0, 0.05],
                                            session.XYZ))
    fit = session.without("validation")
    model = grey_ramp_model(fit, fit.white_XYZ)
    assert np.all(model.black >= 0)
    greys = partial_greys(fit.rgb)
    levels, inverse = np.unique(fit.rgb[greys, 0], return_inverse=True)
    measured = np.array([fit.XYZ[greys][inverse == k].mean(axis=0) for k in range(levels.size)])
    predicted = model.forward(np.repeat(levels[:, None], 3, axis=1))
    # through the greys it was built from (monotone curves: within the greys' own noise)
    assert np.max(np.abs(predicted - measured)) < 0.002 * fit.white_XYZ[1]
    # and on colours it never saw it is no worse than the authors' method, which keeps the black
    rgb = hidden_colours(300, 30006)
    truth = generated.reference_XYZ(rgb)
    ours = np.mean(delta_E2000(model.forward(rgb), truth, fit.white_XYZ))
    theirs = np.mean(delta_E2000(fit_grey_ramp_linearisation(session).forward(rgb), truth,
                                 fit.white_XYZ))
    assert ours <= theirs + 0.01


def test_a_last_reference_read_off_a_decline_is_not_followed_alone():
    # a decline measured to the end, its last reference 3 σ above the trend (through the CS-2000
    # protocol a decline's last white read 1.2 % above the one 16 s before it at 0.4 % noise): a
    # kink at the last inner reference would leave no penalty on the last one, and the curve
    # passed through that reading, where the rows measured last and the reference state are
    times = np.array([48.0, 506, 610, 958, 1062, 1715, 1854, 1960, 2067, 2356, 2460, 2476])
    truth = 1.025 - 0.03 * times / times[-1]
    sd = 0.004
    jumps = []
    for seed in range(20):
        noise = 0.5 * np.random.default_rng(seed).standard_normal(times.size)
        gains = truth * (1.0 + sd * noise)
        gains[-1] = truth[-1] * (1.0 + 3.0 * sd)
        curve = DriftCorrection(times, gains, gains).smoothed_to_noise(np.full(times.size, sd))
        smoothed = curve.gain(times)
        # the curve's step between the last two references, against the readings'
        jumps.append((smoothed[-1] - smoothed[-2]) / (curve.gains[-1] - curve.gains[-2]))
    # (with the kink there: the whole step, 0.98 of it in the median over these seeds; now 0.09)
    assert np.median(jumps) < 0.3 and np.mean(jumps) < 0.3, np.round(jumps, 2)
