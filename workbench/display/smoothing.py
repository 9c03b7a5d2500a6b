"""A penalized smoother whose leave-one-out error comes in closed form.

:func:`whittaker_pinned` fits ``z`` to points ``(x_i, y_i)`` with weights
``w_i`` by minimizing ``Σ w_i (y_i − z_i)² + λ·s·‖D z‖²``: ``D`` the divided
second differences on the (possibly uneven) grid, scaled by the mean spacing
squared so ``λ`` means the same on any grid, and ``s`` the median weight.
The curve is pinned to zero at both ends of the grid (a tone curve's
departure from a reference curve that meets it at 0 and 1). For each
strength ``λ`` of :data:`STRENGTHS` the smoother is linear, ``ẑ = H y``, so
the error of predicting each point from all the others is
``(y_i − ẑ_i) / (1 − H_ii)`` without refitting (Wahba 1990, ch. 4); the
strength with the smallest weighted leave-one-out sum of squares is kept.

References
----------
Whittaker, E. T. (1923). On a new method of graduation. Proceedings of the
Edinburgh Mathematical Society, 41, 63–75.
Wahba, G. (1990). Spline Models for Observational Data. SIAM.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["STRENGTHS", "PinnedSmooth", "weighted_eigenbasis", "whittaker_pinned"]

STRENGTHS = 10.0 ** np.arange(-6.0, 10.01, 0.5)
"""Smoothing strengths tried, from a near-interpolation to a straight line between the pins."""


@dataclass(frozen=True)
class PinnedSmooth:
    """The chosen fit: ``values`` at the interior points, its weighted leave-one-out sum of
    squares, the strength, the effective degrees of freedom (trace of the hat matrix) and
    each point's leave-one-out error."""

    values: np.ndarray
    loo_rss: float
    strength: float
    edf: float
    loo_errors: np.ndarray


def _second_differences(x: np.ndarray) -> np.ndarray:
    """Divided second differences on grid ``x``, scaled by the mean spacing squared."""
    h = np.diff(x)
    n = x.size
    rows = np.zeros((n - 2, n))
    for i in range(n - 2):
        rows[i, i:i + 3] = (1.0 / h[i], -1.0 / h[i] - 1.0 / h[i + 1], 1.0 / h[i + 1])
        rows[i] *= 2.0 / (h[i] + h[i + 1])
    return rows * np.mean(h) ** 2


def weighted_eigenbasis(penalty_rows: np.ndarray, weights: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Λ, U, W^½)``: the eigendecomposition ``U Λ Uᵀ`` of the penalty ``P = Dᵀ D``
    (``penalty_rows`` the rows of ``D``) weighted as ``Q = W^-½ P W^-½``, ``W = diag(weights)``.

    With ``W^½ (W + λP) W^-½ = I + λQ`` the Whittaker smoother's hat ``(W + λP)⁻¹ W`` is
    ``W^-½ U (I + λΛ)⁻¹ Uᵀ W^½`` at every strength ``λ`` (the Demmler–Reinsch basis): one
    symmetric eigendecomposition, then O(n²) a strength rather than a solve. ``Λ`` is clipped
    at zero (``P`` is positive semi-definite)."""
    root = np.sqrt(weights)
    scaled = penalty_rows / root[None, :]
    eigenvalues, vectors = np.linalg.eigh(scaled.T @ scaled)
    return np.maximum(eigenvalues, 0.0), vectors, root


def whittaker_pinned(x, y, weights) -> PinnedSmooth | None:
    """Smooth ``y`` at ``x[1:-1]`` (``weights`` there), pinned to 0 at ``x[0]`` and ``x[-1]``.

    Returns None where there are fewer than three interior points (nothing to smooth).
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    w = np.asarray(weights, dtype=float)
    if x.size < 5 or y.size != x.size - 2 or w.shape != y.shape:
        return None
    penalty_rows = _second_differences(x)[:, 1:-1]  # the pinned ends contribute zero
    # the hat matrix W^-½ U (I + λsΛ)⁻¹ Uᵀ W^½ has the diagonal of U (I + λsΛ)⁻¹ Uᵀ
    eigenvalues, vectors, root = weighted_eigenbasis(penalty_rows, w)
    rotated = vectors.T @ (root * y)
    squares = vectors ** 2
    scale = float(np.median(w))
    best = None
    for strength in STRENGTHS:
        shrink = 1.0 / (1.0 + strength * scale * eigenvalues)
        z = (vectors @ (shrink * rotated)) / root
        leverage = np.clip(squares @ shrink, 0.0, 1.0 - 1e-9)
        errors = (y - z) / (1.0 - leverage)
        loo = float(np.sum(w * errors ** 2))
        if best is None or loo < best.loo_rss:
            best = PinnedSmooth(values=z, loo_rss=loo, strength=float(strength),
                                edf=float(np.sum(shrink)), loo_errors=errors)
    return best
