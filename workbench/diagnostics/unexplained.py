"""``unexplained-residual``: the held-out error is far above what the session's noise explains.

After the final score, the extension's held-out mean ΔE00 is compared with
what measurement noise alone produces on the same colours: each validation
colour, as the extension predicts it, is perturbed :data:`NOISE_DRAWS` times
by the session's noise model (:mod:`workbench.diagnostics.noise`, seeded) and
the mean ΔE00 of those perturbations is the noise's share. The finding is
made when the held-out mean exceeds :data:`UNEXPLAINED_RATIO` times that
share *and* the gap exceeds :data:`UNEXPLAINED_FLOOR_DE00` (the same kind of
materiality floor as the named effects, at a level where a user would see
it). The finding names the gap, where it is largest (by the number of lit
channels and by drive) and the measurements that would identify it: greys
and mixtures at partial drive among the fit rows, which the paper's plan
lacks.

It reads the validation rows once more, after the model is final: it
changes nothing in the model and is reported only.
"""

from __future__ import annotations

import numpy as np

from workbench.colorimetry import delta_E2000
from workbench.diagnostics.detectors import DetectorResult, DiagnosisContext
from workbench.diagnostics.evidence import partial_greys
from workbench.diagnostics.significance import z_of_p

__all__ = ["UNEXPLAINED_RATIO", "UNEXPLAINED_FLOOR_DE00", "NOISE_DRAWS", "noise_share_dE00",
           "unexplained_residual"]

UNEXPLAINED_RATIO = 3.0
"""The held-out mean must exceed this multiple of the noise's share."""

UNEXPLAINED_FLOOR_DE00 = 0.5
"""…and exceed it by at least this mean ΔE00."""

NOISE_DRAWS = 20


def noise_share_dE00(context: DiagnosisContext, predicted: np.ndarray, white: np.ndarray
                     ) -> tuple[float, float]:
    """(mean ΔE00 measurement noise alone adds to colours measured at ``predicted``, its SE).

    Each colour is perturbed :data:`NOISE_DRAWS` times by the session's noise
    model (seeded); the mean CIEDE2000 of the perturbations is the share of a
    held-out error that noise explains.
    """
    rng = np.random.default_rng(20240611)
    covariance = context.noise.covariance(predicted)
    factor = np.linalg.cholesky(covariance + 1e-18 * np.eye(3))
    shocks = rng.standard_normal((NOISE_DRAWS,) + predicted.shape)
    noisy = predicted + np.einsum("nij,knj->kni", factor, shocks)
    reference = np.broadcast_to(predicted, noisy.shape)
    draws = np.asarray(delta_E2000(noisy.reshape(-1, 3), reference.reshape(-1, 3), white)
                       ).reshape(NOISE_DRAWS, -1)
    return float(draws.mean()), float(draws.mean(axis=0).std(ddof=1) if draws.shape[1] > 1 else 0)


def _where(validation, errors: np.ndarray) -> str:
    lit = (validation.rgb > 0).sum(axis=1)
    partial = np.all(validation.rgb < 255, axis=1)
    parts = []
    for label, rows in (("one channel", lit == 1), ("two channels", lit == 2),
                        ("three channels", lit == 3)):
        if rows.sum() >= 3:
            parts.append(f"{label} {errors[rows].mean():.2f}")
    mixtures = (lit >= 2) & partial
    if mixtures.sum() >= 3:
        parts.append(f"mixtures at partial drive {errors[mixtures].mean():.2f}")
    return "; ".join(parts)


def _recommendation(context: DiagnosisContext) -> str:
    rgb = context.raw.rgb
    lit = (rgb > 0).sum(axis=1)
    grey = partial_greys(rgb)
    mixtures = (lit >= 2) & ~grey & np.all(rgb < 255, axis=1)
    wanted = []
    if grey.sum() < 5:
        wanted.append("greys (r = g = b) at partial drive")
    if mixtures.sum() < 10:
        wanted.append("two- and three-channel mixtures at partial drive (e.g. a 5×5×5 cube)")
    if not wanted:
        wanted.append("a repeat of the session (to tell an unstable display from a model gap) "
                      "and denser mixtures where the error is largest")
        return " and ".join(wanted) + " among the fit rows"
    return (" and ".join(wanted) + " among the fit rows (`measure --plan paper+greys` adds "
            "15 greys and 24 partial-drive mixtures to the paper's plan)")


def unexplained_residual(context: DiagnosisContext, model, drift_in_model, validation, white,
                         extended_dE: np.ndarray) -> DetectorResult | None:
    """The ``unexplained-residual`` finding, or None (module doc)."""
    if len(validation) < 5 or extended_dE.size != len(validation):
        return None
    predicted = model.forward(validation.rgb)
    if "temporal-drift" in drift_in_model and validation.t_s is not None:
        predicted = predicted * context.drift.gain(validation.t_s)[:, None]
    share, share_se = noise_share_dE00(context, predicted, white)
    held_out = float(extended_dE.mean())
    gap = held_out - share
    standard_error = float(np.hypot(extended_dE.std(ddof=1) / np.sqrt(extended_dE.size), share_se))
    if not (held_out > UNEXPLAINED_RATIO * share and gap > UNEXPLAINED_FLOOR_DE00):
        return None
    z = gap / standard_error if standard_error > 0 else 37.0
    from scipy.special import ndtr

    p = float(ndtr(-z))
    evidence = (f"held-out mean ΔE00 {held_out:.2f}, of which the session's own noise explains "
                f"{share:.2f}: a gap of {gap:.2f} that no named effect accounts for (by colour: "
                f"{_where(validation, extended_dE)}); to identify it, measure "
                f"{_recommendation(context)}")
    return DetectorResult("unexplained-residual", True, held_out, standard_error, p, z_of_p(p),
                          float(z_of_p(0.05)), True, evidence, significant=True,
                          impact_dE00=gap, details={"noise_share_dE00": share, "gap_dE00": gap,
                                                    "recommendation": _recommendation(context)})
