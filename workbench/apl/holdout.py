"""The APL curve scored on conditions it was not fitted on.

Leave one condition out (a window size, a surround level, or a label a reader
gives): fit the curve on every other row, predict the held-out rows from the
same patch's zero-load output (from the training rows) times the curve's gain
at the held-out load, and score against what was measured. The comparison is
the prediction without a load term: the same patch's mean output over the
training rows.

Errors: luminance in % of the measured luminance; CIEDE2000 in CIELAB whose
reference white is the brightest patch's zero-load XYZ from the training rows
(the display's unlimited white where a white was measured).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.apl.curve import (ChannelTransfer, estimate_transfer, fit_apl_curve, load_rows, patch_keys,
                                 patch_means, unlimited_XYZ)
from workbench.colorimetry import delta_E2000
from workbench.errors import InputError
from workbench.session import Session

__all__ = ["AplHoldoutFold", "AplHoldout", "apl_fold_labels", "evaluate_apl_holdout"]

@dataclass(frozen=True)
class AplHoldoutFold:
    """One held-out condition.

    Attributes
    ----------
    label : str
        The condition held out (e.g. ``window 0.5``).
    rows : int
        Held-out rows scored (patches also measured under other conditions).
    luminance_error_pct, dE00 : float
        Mean absolute luminance error (% of measured) and mean CIEDE2000 with the APL curve.
    luminance_error_pct_without, dE00_without : float
        The same without a load term.
    """

    label: str
    rows: int
    luminance_error_pct: float
    dE00: float
    luminance_error_pct_without: float
    dE00_without: float


@dataclass(frozen=True)
class AplHoldout:
    """Held-out score of the APL curve over every condition of one kind.

    Attributes
    ----------
    by : str
        What was held out (``window size``, ``surround level``, …).
    folds : tuple of AplHoldoutFold
    luminance_error_pct, dE00 : float
        Mean over every held-out row, with the APL curve.
    luminance_error_pct_p95, dE00_p95 : float
        95th percentiles, with the APL curve.
    luminance_error_pct_without, dE00_without : float
        Means without a load term.
    """

    by: str
    folds: tuple
    luminance_error_pct: float
    dE00: float
    luminance_error_pct_p95: float
    dE00_p95: float
    luminance_error_pct_without: float
    dE00_without: float

    def one_line(self) -> str:
        """E.g. ``leave one window size out (5 folds, 90 rows): 3.1 % of luminance, 1.2 ΔE00 ...``."""
        n = sum(f.rows for f in self.folds)
        return (f"leave one {self.by} out ({len(self.folds)} folds, {n} rows): "
                f"{self.luminance_error_pct:.1f} % of luminance, {self.dE00:.2f} ΔE00 mean "
                f"(p95 {self.luminance_error_pct_p95:.1f} %, {self.dE00_p95:.2f}); without a load term "
                f"{self.luminance_error_pct_without:.1f} %, {self.dE00_without:.2f} ΔE00")


def apl_fold_labels(session: Session) -> dict:
    """Condition labels to hold out, by name: the reader's own, else window sizes and surround levels.

    Returns
    -------
    dict of str to ndarray of str
        Only groupings with at least two distinct conditions among the rows
        measured under different frames.
    """
    stated = session.metadata.get("apl_folds")
    if stated:
        return {name: np.asarray(labels, dtype=object) for name, labels in stated.items()}
    rows = load_rows(session).index
    labels = {}
    window = np.array([f"window {w:.3g}" for w in session.window_or_full], dtype=object)
    surround = np.array([f"surround {'/'.join(f'{v:g}' for v in s)}" for s in session.surround_or_black],
                        dtype=object)
    for name, values in (("window size", window), ("surround level", surround)):
        if len(np.unique(values[rows])) >= 2:
            labels[name] = values
    return labels


def evaluate_apl_holdout(session: Session, labels, by: str, *,
                         transfer: ChannelTransfer | None = None) -> AplHoldout:
    """Leave each condition of ``labels`` out in turn and score the APL curve on it.

    Parameters
    ----------
    session : Session
    labels : array_like of str, shape (N,)
        The condition of each row (:func:`apl_fold_labels`).
    by : str
        What the labels are, for the report (``window size``).
    transfer : ChannelTransfer, optional
        As for :func:`~workbench.apl.curve.fit_apl_curve`.

    Returns
    -------
    AplHoldout

    Raises
    ------
    InputError
        When no condition can be held out (fewer than two, or none whose
        patches were measured under another).
    """
    labels = np.asarray(labels, dtype=object)
    transfer = transfer or estimate_transfer(session)
    candidates = load_rows(session).index
    keys = patch_keys(session.rgb)
    folds, lum_all, dE_all, lum0_all, dE0_all = [], [], [], [], []
    for label in sorted(set(labels[candidates])):
        held = labels == label
        train = ~held
        try:
            curve = fit_apl_curve(session, transfer=transfer, rows=train)
        except InputError:
            continue
        patches, zero_load = unlimited_XYZ(session, curve, rows=train)
        lookup = {tuple(p): i for i, p in enumerate(patches)}
        test = [i for i in candidates if held[i] and tuple(keys[i]) in lookup]
        if not test:
            continue
        test = np.array(test)
        which = np.array([lookup[tuple(keys[i])] for i in test])
        gain = curve.gain(curve.load(session.rgb[test], session.window_or_full[test],
                                     session.surround_or_black[test]))
        predicted = zero_load[which] * gain[:, None]
        without = patch_means(session.rgb[train], session.XYZ[train])[1][which]
        white = zero_load[np.argmax(zero_load[:, 1])]
        measured = session.XYZ[test]
        lum = 100.0 * np.abs(predicted[:, 1] - measured[:, 1]) / measured[:, 1]
        lum0 = 100.0 * np.abs(without[:, 1] - measured[:, 1]) / measured[:, 1]
        dE = delta_E2000(predicted, measured, white)
        dE0 = delta_E2000(without, measured, white)
        folds.append(AplHoldoutFold(str(label), len(test), float(lum.mean()), float(dE.mean()),
                                    float(lum0.mean()), float(dE0.mean())))
        lum_all.append(lum), dE_all.append(dE), lum0_all.append(lum0), dE0_all.append(dE0)
    if not folds:
        raise InputError(f"session {session.source!r}: no {by} can be held out (each needs its patches "
                         "measured under another condition too); measure more conditions")
    lum, dE = np.concatenate(lum_all), np.concatenate(dE_all)
    return AplHoldout(by, tuple(folds), float(lum.mean()), float(dE.mean()),
                      float(np.percentile(lum, 95)), float(np.percentile(dE, 95)),
                      float(np.concatenate(lum0_all).mean()), float(np.concatenate(dE0_all).mean()))

