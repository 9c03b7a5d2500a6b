"""The load of a frame: how much of the panel's power a patch on a surround draws.

An OLED panel limits its power (automatic brightness limiting), so what it
shows depends on the frame's average picture level (APL). Here the load of a
frame showing a patch of DAC values ``v`` as a window covering the fraction
``w`` of the field on a surround of DAC values ``s`` is

``load = Σ_c p_c · (w · lin_c(v_c) + (1 − w) · lin_c(s_c))``

with ``lin_c`` the channel's drive-to-linear transfer (0..1) and ``p_c`` the
channel's share of the panel's power at full white (``Σ p_c = 1``), so that a
full-field white is load 1 and black is load 0.

The **reference load** of a patch is the load of the same patch shown full
field (``w = 1``): what a calibration measuring every patch full-field, as the
paper's does, characterizes it at. The rest of the display model is taken to
hold at that load.

Transfers (:data:`CHANNEL_TRANSFERS`): ``power`` (``(v/255)^γ_c``, the gamma
of each channel) and ``pq`` (SMPTE ST 2084, the HDR10 signal: ``v/255`` is the
normalised code value, linear light relative to a stated peak luminance).

Units: DAC values 0..255 (floats allowed); loads and linear drives 0..1.
"""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np

from workbench.errors import InputError

__all__ = [
    "EQUAL_POWER_SHARES",
    "ChannelTransfer",
    "CHANNEL_TRANSFERS",
    "channel_transfer",
    "frame_load",
    "reference_load",
]

EQUAL_POWER_SHARES = (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0)
"""Channel power shares used when the session cannot tell them apart (greys only)."""


@dataclass(frozen=True)
class ChannelTransfer:
    """A drive-to-linear transfer per channel.

    Attributes
    ----------
    method : str
        ``"power"`` or ``"pq"`` (a key of :data:`CHANNEL_TRANSFERS`).
    gammas : (float, float, float)
        Exponents of the ``power`` transfer (unused by ``pq``).
    peak_cd_m2 : float
        Luminance that ``pq`` maps to linear 1 (code values above it saturate).
    """

    method: str = "power"
    gammas: tuple = (2.2, 2.2, 2.2)
    peak_cd_m2: float = 1000.0

    def linear(self, rgb) -> np.ndarray:
        """Linear drive (0..1) of DAC values ``rgb`` (..., 3)."""
        return CHANNEL_TRANSFERS[self.method](np.asarray(rgb, dtype=float), self)

    def to_json(self) -> dict:
        """The transfer as plain JSON types (for profiles and reports)."""
        return {"method": self.method, "gammas": [float(g) for g in self.gammas],
                "peak_cd_m2": float(self.peak_cd_m2)}


def _linear_power(rgb: np.ndarray, transfer: ChannelTransfer) -> np.ndarray:
    return np.clip(rgb / 255.0, 0.0, 1.0) ** np.asarray(transfer.gammas, dtype=float)


def _linear_pq(rgb: np.ndarray, transfer: ChannelTransfer) -> np.ndarray:
    luminance = colour.models.eotf_ST2084(np.clip(rgb / 255.0, 0.0, 1.0))
    return np.minimum(np.asarray(luminance, dtype=float), transfer.peak_cd_m2) / transfer.peak_cd_m2


CHANNEL_TRANSFERS = {
    "power": _linear_power,
    "pq": _linear_pq,
}
"""Drive-to-linear transfers by name."""


def channel_transfer(method: str = "power", **parameters) -> ChannelTransfer:
    """A :class:`ChannelTransfer` by name; an unknown name lists the valid ones."""
    if method not in CHANNEL_TRANSFERS:
        raise InputError(f"unknown channel transfer {method!r}; use one of {', '.join(CHANNEL_TRANSFERS)}")
    return ChannelTransfer(method, **parameters)


def _shares(power_shares) -> np.ndarray:
    shares = np.asarray(power_shares, dtype=float).reshape(3)
    if np.any(shares < 0) or not np.isclose(shares.sum(), 1.0):
        raise InputError(f"channel power shares {shares.tolist()} must be non-negative and sum to 1")
    return shares


def frame_load(rgb, window, surround, transfer: ChannelTransfer,
               power_shares=EQUAL_POWER_SHARES) -> np.ndarray:
    """Load (0..1) of frames showing ``rgb`` as a ``window`` on ``surround``.

    Parameters
    ----------
    rgb : array_like, shape (N, 3)
        Patch DAC values, 0..255.
    window : array_like, shape (N,)
        The patch's fraction of the field, 0 < window <= 1.
    surround : array_like, shape (N, 3)
        Surround DAC values, 0..255.
    transfer : ChannelTransfer
    power_shares : array_like, shape (3,)
        Each channel's share of the panel power at full white (sums to 1).

    Returns
    -------
    ndarray, shape (N,)
        1 for full-field white, 0 for black.
    """
    window = np.asarray(window, dtype=float).reshape(-1, 1)
    linear = window * transfer.linear(rgb) + (1.0 - window) * transfer.linear(surround)
    return linear.reshape(-1, 3) @ _shares(power_shares)


def reference_load(rgb, transfer: ChannelTransfer, power_shares=EQUAL_POWER_SHARES) -> np.ndarray:
    """Load of each patch shown full field: the load the rest of the display model assumes."""
    rgb = np.asarray(rgb, dtype=float).reshape(-1, 3)
    return frame_load(rgb, np.ones(len(rgb)), np.zeros_like(rgb), transfer, power_shares)
