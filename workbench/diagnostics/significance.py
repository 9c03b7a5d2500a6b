"""When a detector's statistic is evidence: significance over all detectors, and materiality.

A finding needs both:

- **significance**: the detector's p-value (from its statistic, a standard
  error propagated from the session's noise model, and the test's null
  distribution) is at most ``FAMILY_ALPHA / m`` over the ``m`` detectors that
  could be tested (Bonferroni), so the chance of *any* false finding in a
  clean session stays at or below :data:`FAMILY_ALPHA` (5 %), whatever the
  detectors' dependence. ``z`` is the one-sided normal quantile of the
  p-value, compared with the critical ``z`` of ``FAMILY_ALPHA / m``;
- **materiality**: the term's effect on colours, the mean CIEDE2000 between
  the model with and without it over :data:`FIXED_COLOURS` (a 5 × 5 × 5 cube
  of DAC values that does not depend on any row of the session), is at least
  :data:`MATERIALITY_FLOOR_DE00`.

The chi-square, F and normal tail functions come from :mod:`scipy.special`
(their ``scipy.stats`` wrappers cost a third of a second to import).
"""

from __future__ import annotations

import numpy as np
from scipy.special import chdtrc, fdtrc, ndtri, stdtr

__all__ = [
    "FAMILY_ALPHA",
    "MATERIALITY_FLOOR_DE00",
    "FIXED_COLOURS",
    "critical_p",
    "z_of_p",
    "z_of_chi2",
    "chi2_sf",
    "f_sf",
    "t_sf",
    "mean_dE00_on_fixed_colours",
]

FAMILY_ALPHA = 0.05
"""Chance of any false finding in a clean session, over all detectors together."""

MATERIALITY_FLOOR_DE00 = 0.05
"""A finding must change the colours of :data:`FIXED_COLOURS` by at least this mean ΔE00 (a
twentieth of a just-noticeable difference on average, several times that on the colours the
effect touches)."""

_LEVELS = np.array([0.0, 64.0, 128.0, 191.0, 255.0])
FIXED_COLOURS = np.stack(np.meshgrid(_LEVELS, _LEVELS, _LEVELS, indexing="ij"),
                         axis=-1).reshape(-1, 3)
"""The 125 DAC triplets materiality is measured on (never the session's validation colours)."""


def critical_p(tested: int, alpha: float = FAMILY_ALPHA) -> float:
    """Per-detector significance level for ``tested`` detectors (Bonferroni)."""
    return alpha / max(int(tested), 1)


def z_of_p(p: float) -> float:
    """One-sided standard-normal quantile of a p-value (capped at 37 for p → 0)."""
    p = float(np.clip(p, 1e-300, 1.0))
    return float(min(-ndtri(p), 37.0)) if p < 1.0 else float("-inf")


def z_of_chi2(value: float, dof: int) -> float:
    """One-sided z of a χ² value: exact through the p-value, Wilson–Hilferty where p underflows."""
    p = chi2_sf(value, dof)
    if p > 1e-15:
        return z_of_p(p)
    k = float(dof)
    return float(((value / k) ** (1 / 3) - (1 - 2 / (9 * k))) / np.sqrt(2 / (9 * k)))


def chi2_sf(value: float, dof: int) -> float:
    """Upper tail of χ² with ``dof`` degrees of freedom."""
    return float(chdtrc(dof, max(float(value), 0.0)))


def f_sf(value: float, dfn: int, dfd: int) -> float:
    """Upper tail of Fisher's F(``dfn``, ``dfd``)."""
    return float(fdtrc(dfn, max(dfd, 1), max(float(value), 0.0)))


def t_sf(value: float, dof: float) -> float:
    """Upper tail of Student's t with ``dof`` degrees of freedom (one-sided p of ``value``)."""
    return float(stdtr(dof, -float(value)))


def mean_dE00_on_fixed_colours(XYZ_a: np.ndarray, XYZ_b: np.ndarray, white: np.ndarray) -> float:
    """Mean CIEDE2000 between two predictions of :data:`FIXED_COLOURS` (CIELAB white ``white``)."""
    from workbench.colorimetry import delta_E2000

    return float(np.mean(delta_E2000(XYZ_a, XYZ_b, white)))
