"""The exported power-limit model is fitted on every row that carries the load law, in X, Y and Z.

A power limit is *identified* on the sweeps and the white alone (every plan has them), but the
model exported and cross-validated (:func:`~workbench.diagnostics.power_limit.power_limit_model`)
also reads the greys and partial-drive mixtures, whose loads reach the white's, and the X and Z
of every row: the undimmed primaries' chromaticities are then averaged over every bright reading
rather than taken from one reading at full drive. On the adaptive plan's core (ten levels per
channel and a grey ramp) a luminance fit of the sweeps and the white traded the load law's knee
against its shape and misplaced the green primary's undimmed output by half a per cent.

A power limit whose knee lies above every channel's own share of the white leaves the sweeps
untouched: no bend to explain, so the greys and mixtures that load the panel beyond the knee
must show it (:func:`~workbench.diagnostics.power_limit.mixtures_show_load_gain`), and the
model choice is then offered the power-limit model.

The display here is written for this test, unlike the independent generator's and unlike the
model's own form: the load gain is ``exp(−c · load^1.6)`` (no knee, no clipped power), the
instrument's luminance noise is Student-t and its chromaticity noise is drawn in x and y.
"""

import numpy as np
import pytest

from workbench.colorimetry import delta_E2000
from workbench.diagnostics.detectors import build_context
from workbench.diagnostics import diagnose
from workbench.diagnostics.power_limit import (
    fit_power_limit,
    mixtures_show_load_gain,
    power_limit_model,
    tone_bend_explained,
)
from workbench.session import Session

LEVELS = (32, 64, 96, 128, 160, 192, 208, 224, 236, 246)  # the adaptive core's sweep levels
GREYS = (16, 32, 48) + tuple(range(64, 241, 16))
PRIMARIES_xyY = np.array([[0.655, 0.335, 0.245], [0.300, 0.610, 0.685], [0.150, 0.055, 0.070]])


class _SaturatingLimit:
    """Power-law channels dimmed together by ``exp(−c · load^1.6)``; load 1 at white."""

    def __init__(self, seed, knee=None):
        rng = np.random.default_rng(seed)
        self.gamma = rng.uniform(1.9, 2.5, 3)
        xyY = PRIMARIES_xyY.copy()
        xyY[:, :2] += rng.uniform(-0.01, 0.01, (3, 2))
        x, y, Y = xyY.T
        self.P = 100 * np.column_stack([x * Y / y, Y, (1 - x - y) * Y / y])  # undimmed XYZ
        self.c = rng.uniform(0.06, 0.14)
        self.knee = knee  # a high knee: the loss grows as (load − knee)^1.5 past it

    def XYZ(self, rgb):
        L = np.clip(np.asarray(rgb, dtype=float) / 255.0, 0, 1) ** self.gamma
        load = L @ self.P[:, 1] / self.P[:, 1].sum()
        if self.knee is None:
            gain = np.exp(-self.c * load ** 1.6)
        else:
            gain = 1 - self.c * (np.clip(load - self.knee, 0, None) / (1 - self.knee)) ** 1.5
        return (L @ self.P) * gain[:, None] + np.array([0.02, 0.02, 0.03])


def _measured(display, rgb, rng):
    XYZ = display.XYZ(rgb)
    gain = 1 + 0.0015 * rng.standard_t(4, len(rgb))
    S = XYZ.sum(axis=1)
    x = XYZ[:, 0] / S + 2e-4 * rng.standard_normal(len(rgb))
    y = XYZ[:, 1] / S + 2e-4 * rng.standard_normal(len(rgb))
    Y = XYZ[:, 1] * gain
    floor = 0.002 * rng.standard_normal((len(rgb), 3))
    return np.column_stack([x * Y / y, Y, (1 - x - y) * Y / y]) + floor


def _session(display, seed, mixtures=()):
    rows = [("black", (0, 0, 0)), ("white", (255, 255, 255))]
    for c, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        for level in (255, *LEVELS):
            rgb = [0, 0, 0]
            rgb[c] = level
            rows.append((kind, tuple(rgb)))
        rows.append(("white", (255, 255, 255)))
    rows += [("grey", (v, v, v)) for v in GREYS] + [("white", (255, 255, 255))]
    rows += [("mixture", rgb) for rgb in mixtures]
    rgb = np.array([r for _, r in rows], dtype=float)
    return Session(kind=np.array([k for k, _ in rows], dtype=object), rgb=rgb,
                   XYZ=_measured(display, rgb, np.random.default_rng(seed + 100)),
                   t_s=np.arange(len(rows), dtype=float) * 5.0, source=f"saturating limit {seed}",
                   metadata={})


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_exported_power_limit_reads_the_greys_and_the_chromaticities(seed):
    display = _SaturatingLimit(seed)
    context = build_context(_session(display, seed), drift_found=False)
    explained, why, sweeps_fit = tone_bend_explained(context)
    assert explained, why  # identified on the sweeps and the white, as before
    hidden = np.random.default_rng(seed + 200).uniform(0, 255, (300, 3))
    truth = display.XYZ(hidden)
    white = display.XYZ(np.full((1, 3), 255.0))[0]

    def error(model):
        return float(np.mean(delta_E2000(model.forward(hidden), truth, white)))

    exported = error(power_limit_model(context))
    from_sweeps = error(power_limit_model(context, fit=sweeps_fit))  # the sweeps' and white's Y
    assert exported < 0.6 * from_sweeps, (exported, from_sweeps)
    assert exported < 0.06, exported
    # the greys in the luminance fit without X and Z: the chromaticities still matter
    greys_in_Y = error(power_limit_model(context, fit=fit_power_limit(context, mixtures=True)))
    assert exported < greys_in_Y, (exported, greys_in_Y)


MIXTURES = [(r, g, b) for r in (128, 192, 255) for g in (128, 192, 255) for b in (128, 192, 255)
            if (r, g, b) != (255, 255, 255) and not r == g == b]  # a follow-up's cube


def test_a_knee_above_every_channel_is_offered_from_the_greys():
    """A knee at 82 % load: no sweep reaches it, the greys and a follow-up's mixtures do.

    Offered so, the power-limit model must beat the extension beyond noise: on these six
    displays it does on five (on the sixth by 0.19 ± 0.11, and the extension is exported)."""
    taken = 0
    for seed in range(6):
        display = _SaturatingLimit(seed, knee=0.82)
        session = _session(display, seed, MIXTURES)
        context = build_context(session, drift_found=False)
        assert not tone_bend_explained(context)[0]  # the sweeps carry no bend
        shown, why, _ = mixtures_show_load_gain(context)
        assert shown, why
        diagnosis = diagnose(session)
        chosen = diagnosis.model_choice.chosen == "power-limit"
        taken += chosen
        hidden = np.random.default_rng(seed + 300).uniform(0, 255, (300, 3))
        truth = display.XYZ(hidden)
        white = display.XYZ(np.full((1, 3), 255.0))[0]
        exported = float(np.mean(delta_E2000(diagnosis.extended.forward(hidden), truth, white)))
        baseline = float(np.mean(delta_E2000(diagnosis.baseline.forward(hidden), truth, white)))
        assert exported < 0.08, (seed, exported)
        # taken, it gains the 30 % on hidden colours (the limit dims only colours near
        # white, so the paper's model is not far off elsewhere: gains of 44-83 % here)
        assert exported < 0.7 * baseline or not chosen, (seed, exported, baseline)
    assert taken >= 4, taken


@pytest.mark.parametrize("seed", [0, 1])
def test_additive_greys_show_no_load_gain(seed):
    display = _SaturatingLimit(seed)
    display.c = 0.0
    context = build_context(_session(display, seed, MIXTURES), drift_found=False)
    shown, why, _ = mixtures_show_load_gain(context)
    assert not shown, why


def test_the_black_rows_noise_does_not_tint_the_primaries():
    """Every row is black-subtracted with the black rows' reading, whose floor noise differs in
    X, Y and Z; dense sweeps' dark points carry it in their chromaticity. The fit frees the
    black offset in all three, so the primaries' chromaticities come from the bright rows."""
    display = _SaturatingLimit(4)
    rows = [("black", (0, 0, 0)), ("white", (255, 255, 255))]
    for c, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        for level in range(5, 256, 5):
            rgb = [0, 0, 0]
            rgb[c] = level
            rows.append((kind, tuple(rgb)))
        rows.append(("white", (255, 255, 255)))
    rows += [("grey", (v, v, v)) for v in range(16, 241, 16)] + [("white", (255, 255, 255))]
    rgb = np.array([r for _, r in rows], dtype=float)
    rng = np.random.default_rng(7)
    XYZ = _measured(display, rgb, rng)
    XYZ[0] = display.XYZ(rgb[:1])[0] + np.array([0.012, -0.012, -0.011])  # the black, read off
    session = Session(kind=np.array([k for k, _ in rows], dtype=object), rgb=rgb, XYZ=XYZ,
                      t_s=np.arange(len(rows), dtype=float) * 5.0, source="dense sweeps",
                      metadata={})
    context = build_context(session, drift_found=False)
    model = power_limit_model(context)
    true_xy = display.P[:, :2] / display.P.sum(axis=1, keepdims=True)
    fitted = np.array([model.forward(np.diag([255.0] * 3)[c][None])[0] - model.forward(
        np.zeros((1, 3)))[0] for c in range(3)])
    fitted_xy = fitted[:, :2] / fitted.sum(axis=1, keepdims=True)
    assert np.max(np.abs(fitted_xy - true_xy)) < 4e-4, fitted_xy - true_xy
