"""``apl-dependence``: does the same patch's output change with the rest of the picture?

The test (a z-test against the session's own noise): over every patch
measured under at least two different frames (window sizes, surrounds), the
log luminance is regressed on the frame's load within each patch (one
intercept per patch, one common slope ``β``). With a relative measurement
noise ``σ`` (standard deviation of ``ΔY/Y`` for one measurement), the slope's
standard error is ``σ / sqrt(Σ (L − L̄_patch)²)``; with a noise per row
``σ_i`` (dim rows are noisier), ``sqrt(Σ c_i² σ_i²) / Σ c_i²`` with ``c_i`` the
centred loads (the least-squares slope's exact standard error). The statistic is ``−β``: the
loss of ln luminance per unit of load (from black to a full-field white;
about the fractional loss when small), ``z = −β / SE``; an OLED's power
limiting makes it positive.

The statistic is a linear summary of what is usually a knee-shaped curve
(:mod:`workbench.apl.curve`): it tests whether there is a dependence, the
curve says what it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from workbench.apl.curve import estimate_transfer, load_rows
from workbench.apl.load import EQUAL_POWER_SHARES, frame_load
from workbench.colorimetry import delta_E2000
from workbench.errors import InputError
from workbench.session import Session

__all__ = ["AplDependenceTest", "detect_apl_dependence"]

EFFECT_ID = "apl-dependence"


@dataclass(frozen=True)
class AplDependenceTest:
    """The ``apl-dependence`` test of one session.

    Attributes
    ----------
    statistic : float
        Loss of ln luminance per unit of load (0.2: a patch is about 20 %
        dimmer in a full white field than alone on black); 0 when not testable.
    standard_error : float
        Its standard error from the given relative noise (``inf`` when not testable).
    z : float
        ``statistic / standard_error`` (0 when not testable).
    impact_dE00 : float
        Mean CIEDE2000 between each patch at its lowest and at its highest
        measured load (reference white: the brightest row).
    evidence : str
        One sentence with the numbers.
    testable : bool
        Whether any patch was measured under two frames.
    rows, patches : int
        Rows and distinct patches the test used.
    """

    statistic: float
    standard_error: float
    z: float
    impact_dE00: float
    evidence: str
    testable: bool = True
    rows: int = 0
    patches: int = 0
    effect: str = EFFECT_ID


def detect_apl_dependence(session: Session, relative_noise) -> AplDependenceTest:
    """Test whether the same patch's output varies with the frame's load beyond noise.

    Parameters
    ----------
    session : Session
        With ``window``/``surround`` columns (drift-corrected if it drifts).
    relative_noise : float or array_like, shape (N,)
        Standard deviation of one measurement's relative luminance error
        (e.g. 0.002 for 0.2 %), estimated from the session's own repeats; or
        one per session row (from the session's noise model).

    Returns
    -------
    AplDependenceTest
        Compare ``z`` with the significance threshold of the caller.

    Raises
    ------
    InputError
        For a relative noise that is not a positive finite number.
    """
    noise = np.broadcast_to(np.asarray(relative_noise, dtype=float), (len(session),))
    if not np.all(np.isfinite(noise) & (noise > 0)):
        raise InputError(f"relative_noise {relative_noise!r} must be positive numbers "
                         "(the standard deviation of ΔY/Y of one measurement, e.g. 0.002)")
    data = load_rows(session)
    if len(data) == 0:
        return AplDependenceTest(0.0, math.inf, 0.0, 0.0,
                                 "not testable: no patch was measured under two different frames "
                                 "(window sizes or surrounds); measure the 'apl' plan",
                                 testable=False)
    transfer = estimate_transfer(session)
    load = frame_load(data.rgb, data.window, data.surround, transfer, EQUAL_POWER_SHARES)
    log_Y = np.log(data.XYZ[:, 1])
    counts = np.bincount(data.group)
    load_centred = load - (np.bincount(data.group, weights=load) / counts)[data.group]
    log_centred = log_Y - (np.bincount(data.group, weights=log_Y) / counts)[data.group]
    spread = float(np.sum(load_centred ** 2))
    if spread <= 0:
        return AplDependenceTest(0.0, math.inf, 0.0, 0.0,
                                 "not testable: the frames of each patch have the same load",
                                 testable=False, rows=len(data), patches=len(counts))
    slope = float(np.sum(load_centred * log_centred) / spread)
    statistic = -slope
    standard_error = math.sqrt(float(np.sum(load_centred ** 2 * noise[data.index] ** 2))) / spread
    z = statistic / standard_error
    impact, low_high = _impact(data, load)
    patches = len(counts)
    (Y_low, L_low), (Y_high, L_high) = low_high
    change = 100.0 * (Y_high / Y_low - 1.0)
    evidence = (f"the same patch's ln luminance changes by {-statistic:+.3f} ± {standard_error:.3f} per unit of "
                f"the frame's load (0 = black, 1 = full-field white; z = {z:.1f}) over {len(data)} rows of "
                f"{patches} patches measured under different frames; the brightest patch gives "
                f"{Y_low:.4g} cd/m² at load {L_low:.3f} and {Y_high:.4g} cd/m² at load {L_high:.3f} "
                f"({change:+.1f} %); mean impact {impact:.2f} ΔE00")
    return AplDependenceTest(statistic, standard_error, z, impact, evidence, rows=len(data), patches=patches)


def _impact(data, load: np.ndarray) -> tuple[float, tuple]:
    """Mean ΔE00 between each patch's lowest- and highest-load rows, and the brightest patch's pair."""
    white = data.XYZ[np.argmax(data.XYZ[:, 1])]
    lows, highs = [], []
    for g in np.unique(data.group):
        rows = np.flatnonzero(data.group == g)
        lows.append(rows[np.argmin(load[rows])])
        highs.append(rows[np.argmax(load[rows])])
    lows, highs = np.array(lows), np.array(highs)
    dE = delta_E2000(data.XYZ[lows], data.XYZ[highs], white)
    top = int(np.argmax(data.XYZ[lows, 1]))
    pair = ((float(data.XYZ[lows[top], 1]), float(load[lows[top]])),
            (float(data.XYZ[highs[top], 1]), float(load[highs[top]])))
    return float(np.mean(dE)), pair
