"""The APL curve: a display's output gain as a function of the frame's load.

Model (``soft power cap``)::

    gain(L) = (1 + (L / L0)^n)^(−a/n)

``gain → 1`` for loads well below the knee ``L0`` and ``gain → (L0 / L)^a``
above it: ``a = 1`` is a panel that holds its power constant beyond the knee,
``a < 1`` one that lets the power grow; ``n`` sets how sharp the knee is. The
curve is fitted on the same patches measured at different loads (see
:mod:`workbench.apl.load`), with each patch's unlimited output profiled out,
so it needs no display model: ``Y_i = U_patch · gain(L_i)``.

A patch shown at load ``L`` shows ``gain(L) / gain(L_ref)`` of what it shows
full field (``L_ref``, :func:`~workbench.apl.load.reference_load`), which is
what a model fitted on full-field patches predicts.

Units: loads 0..1 (full-field white = 1); XYZ absolute (cd/m² for Y).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from workbench.apl.load import (EQUAL_POWER_SHARES, ChannelTransfer, frame_load,
                                reference_load)
from workbench.errors import InputError
from workbench.session import Session

__all__ = [
    "AplCurve",
    "LoadRows",
    "MIN_RELATIVE_LUMINANCE",
    "estimate_transfer",
    "load_rows",
    "fit_apl_curve",
    "patch_keys",
    "patch_means",
    "unlimited_XYZ",
]

MIN_RELATIVE_LUMINANCE = 0.02
"""Rows dimmer than this fraction of the session's brightest are left out of APL fits and tests
(their relative noise is far above a bright patch's)."""

_PATCH_DECIMALS = 2  # DAC values equal to this many decimals are the same patch
_KNEE_LIMITS = (1e-3, 10.0)
_SHARPNESS_LIMITS = (0.5, 30.0)
_EXPONENT_LIMITS = (0.0, 3.0)
_KNEE_STARTS = (0.05, 0.2, 0.6)


@dataclass(frozen=True)
class AplCurve:
    """Output gain against load, with the load's definition.

    Attributes
    ----------
    knee : float
        ``L0``, the load where limiting sets in (0..1 scale; may exceed 1 for
        a panel that barely limits).
    sharpness : float
        ``n``: how abruptly the limiting sets in.
    exponent : float
        ``a``: gain falls as ``L^−a`` well above the knee (0 = no limiting).
    transfer : ChannelTransfer
        Drive-to-linear transfer used for the load.
    power_shares : tuple of float
        Channel shares of the panel power at full white.
    fitted_on : str
        What the curve was fitted on.
    """

    knee: float
    sharpness: float
    exponent: float
    transfer: ChannelTransfer = field(default_factory=ChannelTransfer)
    power_shares: tuple = EQUAL_POWER_SHARES
    fitted_on: str = ""

    def gain(self, load) -> np.ndarray:
        """Output gain (1 at zero load) at ``load`` (0..1)."""
        return _gain(np.asarray(load, dtype=float), self.knee, self.sharpness, self.exponent)

    def load(self, rgb, window, surround) -> np.ndarray:
        """Load of frames showing ``rgb`` as ``window`` on ``surround`` (see :func:`frame_load`)."""
        return frame_load(rgb, window, surround, self.transfer, self.power_shares)

    def reference_load(self, rgb) -> np.ndarray:
        """Load of each patch shown full field: what the rest of the model assumes."""
        return reference_load(rgb, self.transfer, self.power_shares)

    def relative_gain(self, rgb, window, surround) -> np.ndarray:
        """Output of ``rgb`` on ``window``/``surround`` relative to the same patch full field."""
        rgb = np.asarray(rgb, dtype=float).reshape(-1, 3)
        return self.gain(self.load(rgb, window, surround)) / self.gain(self.reference_load(rgb))

    def to_json(self) -> dict:
        """The curve as plain JSON types (for a profile's APL block or a bundle)."""
        return {"model": "soft-power-cap", "formula": "gain = (1 + (L/L0)^n)^(-a/n)",
                "knee": float(self.knee), "sharpness": float(self.sharpness),
                "exponent": float(self.exponent), "power_shares": [float(s) for s in self.power_shares],
                "transfer": self.transfer.to_json(),
                "reference_load": "each patch full field (window 1): the load the display model assumes",
                "fitted_on": self.fitted_on}


def _gain(load, knee, sharpness, exponent):
    load = np.maximum(load, 0.0)
    return np.exp(-(exponent / sharpness) * np.log1p((load / knee) ** sharpness))


@dataclass(frozen=True)
class LoadRows:
    """The rows of a session that show the same patch at different loads.

    Attributes
    ----------
    index : ndarray of int
        Row numbers in the session.
    group : ndarray of int
        Patch number of each row (rows of one patch share it).
    rgb, window, surround, XYZ : ndarray
        Those rows' values.
    """

    index: np.ndarray
    group: np.ndarray
    rgb: np.ndarray
    window: np.ndarray
    surround: np.ndarray
    XYZ: np.ndarray

    def __len__(self) -> int:
        return len(self.index)

    def subset(self, mask) -> "LoadRows":
        """The rows where ``mask`` is true."""
        mask = np.asarray(mask, dtype=bool)
        return LoadRows(self.index[mask], self.group[mask], self.rgb[mask], self.window[mask],
                        self.surround[mask], self.XYZ[mask])


def load_rows(session: Session, min_relative_luminance: float = MIN_RELATIVE_LUMINANCE) -> LoadRows:
    """Rows of patches measured under at least two different frames (window or surround).

    Rows dimmer than ``min_relative_luminance`` of the brightest row are left
    out; so are patches measured under one frame only.
    """
    window = session.window_or_full
    surround = session.surround_or_black
    Y = session.XYZ[:, 1]
    bright = Y >= min_relative_luminance * max(float(Y.max()), 1e-300)
    key_patch = patch_keys(session.rgb)
    frame = np.column_stack([np.round(window, 6), np.round(surround, _PATCH_DECIMALS)])
    _, patch_id = np.unique(key_patch, axis=0, return_inverse=True)
    patch_id = patch_id.reshape(-1)
    keep = np.zeros(len(session), dtype=bool)
    for p in np.unique(patch_id[bright]):
        rows = np.flatnonzero((patch_id == p) & bright)
        if len(np.unique(frame[rows], axis=0)) >= 2:
            keep[rows] = True
    index = np.flatnonzero(keep)
    _, group = np.unique(patch_id[index], return_inverse=True)
    return LoadRows(index, group.reshape(-1), session.rgb[index], window[index], surround[index],
                    session.XYZ[index])


def estimate_transfer(session: Session) -> ChannelTransfer:
    """The drive-to-linear transfer of the session's display, for the load.

    A transfer the reader states (``metadata["transfer"]``, e.g. PQ for an
    HDR10 signal) wins; otherwise a power law per channel fitted on the
    full-field single-channel ramps, else one for all channels fitted on the
    greys (each grey level's brightest measurement, the least limited), else
    2.2.
    """
    stated = session.metadata.get("transfer")
    if isinstance(stated, ChannelTransfer):
        return stated
    if isinstance(stated, dict):
        return ChannelTransfer(stated.get("method", "power"), tuple(stated.get("gammas", (2.2,) * 3)),
                               float(stated.get("peak_cd_m2", 1000.0)))
    full = session.window_or_full >= 1.0
    black_Y = float(session.black_XYZ[1])
    gammas = []
    for channel, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        rows = session.mask(kind) & full
        gammas.append(_power_law_exponent(session.rgb[rows, channel], session.XYZ[rows, 1] - black_Y))
    if all(g is not None for g in gammas):
        return ChannelTransfer("power", tuple(gammas))
    grey = np.ptp(session.rgb, axis=1) == 0
    levels = np.unique(session.rgb[grey, 0])
    brightest = np.array([session.XYZ[grey & (session.rgb[:, 0] == v), 1].max() for v in levels]) \
        if len(levels) else np.array([])
    gamma = _power_law_exponent(levels, brightest - black_Y) if len(levels) else None
    return ChannelTransfer("power", (gamma or 2.2,) * 3)


def _power_law_exponent(dac: np.ndarray, Y: np.ndarray) -> float | None:
    """Exponent of ``Y/Y_max = (dac/dac_max)^γ`` on levels above 2 % of the maximum, or None."""
    if len(dac) < 3 or np.max(dac) <= 0:
        return None
    top = np.argmax(dac)
    if Y[top] <= 0:
        return None
    d, y = dac / 255.0, Y / Y[top]
    ok = (d > 0) & (d < dac[top] / 255.0) & (y > 0.02)
    if ok.sum() < 2:
        return None
    x = np.log(d[ok] / (dac[top] / 255.0))
    return float(np.sum(x * np.log(y[ok])) / np.sum(x * x))


def _profiled_residuals(log_Y: np.ndarray, log_gain: np.ndarray, group: np.ndarray) -> np.ndarray:
    corrected = log_Y - log_gain
    means = np.bincount(group, weights=corrected) / np.bincount(group)
    return corrected - means[group]


def _shares_from(free: np.ndarray) -> np.ndarray:
    e = np.exp(np.r_[free, 0.0])
    return e / e.sum()


def fit_apl_curve(session: Session, *, transfer: ChannelTransfer | None = None,
                  rows: np.ndarray | None = None, fit_power_shares: bool | None = None) -> AplCurve:
    """Fit the APL curve on the patches a session measured at different loads.

    Parameters
    ----------
    session : Session
        With ``window`` and/or ``surround`` columns.
    transfer : ChannelTransfer, optional
        Drive-to-linear transfer for the load; :func:`estimate_transfer` by default.
    rows : array_like of bool, optional
        Fit on these session rows only (e.g. all but a held-out condition).
    fit_power_shares : bool, optional
        Fit the channels' power shares too; by default only when the rows
        differ in colour (greys alone cannot tell the channels apart).

    Returns
    -------
    AplCurve

    Raises
    ------
    InputError
        When no patch was measured under two different frames.
    """
    transfer = transfer or estimate_transfer(session)
    data = load_rows(session)
    if rows is not None:
        data = data.subset(np.asarray(rows, dtype=bool)[data.index])
        _, group = np.unique(data.group, return_inverse=True)
        data = LoadRows(data.index, group.reshape(-1), data.rgb, data.window, data.surround, data.XYZ)
    counts = np.bincount(data.group) if len(data) else np.array([])
    if len(data) == 0 or not np.any(counts >= 2):
        raise InputError(f"session {session.source!r}: no patch was measured under two different frames "
                         "(window sizes or surrounds); measure with the 'apl' plan to fit an APL curve")
    linear_patch = transfer.linear(data.rgb)
    linear_surround = transfer.linear(data.surround)
    w = data.window[:, None]
    per_channel = w * linear_patch + (1.0 - w) * linear_surround
    coloured = bool(np.any(np.ptp(data.rgb, axis=1) > 0) or np.any(np.ptp(data.surround, axis=1) > 0))
    if fit_power_shares is None:
        fit_power_shares = coloured
    log_Y = np.log(data.XYZ[:, 1])

    def unpack(p):
        shares = _shares_from(p[3:]) if fit_power_shares else np.asarray(EQUAL_POWER_SHARES)
        return np.exp(p[0]), p[1], p[2], shares

    def residuals(p):
        knee, sharpness, exponent, shares = unpack(p)
        log_gain = np.log(_gain(per_channel @ shares, knee, sharpness, exponent))
        return _profiled_residuals(log_Y, log_gain, data.group)

    lower = [np.log(_KNEE_LIMITS[0]), _SHARPNESS_LIMITS[0], _EXPONENT_LIMITS[0]]
    upper = [np.log(_KNEE_LIMITS[1]), _SHARPNESS_LIMITS[1], _EXPONENT_LIMITS[1]]
    if fit_power_shares:
        lower += [-4.0, -4.0]
        upper += [4.0, 4.0]
    best = None
    for knee0 in _KNEE_STARTS:
        start = [np.log(knee0), 2.0, 0.5] + ([0.0, 0.0] if fit_power_shares else [])
        fit = least_squares(residuals, start, bounds=(lower, upper))
        if best is None or fit.cost < best.cost:
            best = fit
    knee, sharpness, exponent, shares = unpack(best.x)
    n_patches = len(np.unique(data.group))
    return AplCurve(float(knee), float(sharpness), float(exponent), transfer,
                    tuple(float(s) for s in shares),
                    f"{len(data)} rows of {n_patches} patches measured under different frames")


def unlimited_XYZ(session: Session, curve: AplCurve, rows=None) -> tuple[np.ndarray, np.ndarray]:
    """Each patch's output at zero load, from its rows divided by the curve's gain.

    Parameters
    ----------
    session : Session
    curve : AplCurve
    rows : array_like of bool, optional
        Use only these rows (e.g. the training rows of a held-out test).

    Returns
    -------
    (ndarray, ndarray)
        The distinct patches' DAC values (P, 3) and their zero-load XYZ (P, 3).
    """
    mask = np.ones(len(session), dtype=bool) if rows is None else np.asarray(rows, dtype=bool)
    rgb = session.rgb[mask]
    gain = curve.gain(curve.load(rgb, session.window_or_full[mask], session.surround_or_black[mask]))
    return patch_means(rgb, session.XYZ[mask] / gain[:, None])


def patch_keys(rgb) -> np.ndarray:
    """DAC values rounded so that rows of the same patch compare equal."""
    return np.round(rgb, _PATCH_DECIMALS)


def patch_means(rgb, XYZ) -> tuple[np.ndarray, np.ndarray]:
    """The distinct patches (:func:`patch_keys`, in ``np.unique`` order) and each one's mean ``XYZ``."""
    patches, inverse = np.unique(patch_keys(rgb), axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    totals = np.zeros((len(patches), 3))
    np.add.at(totals, inverse, XYZ)
    return patches, totals / np.bincount(inverse)[:, None]
