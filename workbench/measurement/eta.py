"""How long the rest of a measurement run will take: dark patches take longer.

A spectroradiometer integrates longer on dark patches (the CS-2000 from about
a second on a bright white up to 242 s near black), so the remaining time of a
run depends on which patches remain, not only on how many. The model here
learns, from the patches measured so far, how the wall-clock time per patch
depends on the patch's luminance relative to white, and sums that over the
patches still to go, each placed by its expected relative luminance.

The expected relative luminance of a patch is ``Σ_c w_c (v_c / 255)^γ`` with
``γ =`` :data:`RANKING_GAMMA` and ``w_c`` each channel's share of white,
measured from the full-drive ramp patches once they are done (Rec. 709
luminance coefficients before that). It only ranks patches by brightness for
the estimate; it is not a display model.
"""

from __future__ import annotations

import numpy as np

from workbench.measurement.plans import Patch

__all__ = ["RANKING_GAMMA", "PRIOR_CHANNEL_SHARES", "PatchDurationModel"]

RANKING_GAMMA = 2.2
"""Tone-curve exponent used to rank patches by expected brightness."""

PRIOR_CHANNEL_SHARES = (0.2126, 0.7152, 0.0722)
"""Channel shares of white luminance before the primaries are measured (ITU-R BT.709)."""

_DARKEST_RELATIVE = 1e-6  # relative luminances below this rank as equally dark (and log10 stays finite)
_RAMP_CHANNEL = {"ramp-r": 0, "ramp-g": 1, "ramp-b": 2}


class PatchDurationModel:
    """Learns seconds per patch against relative luminance, and predicts what remains.

    Examples
    --------
    >>> model = PatchDurationModel()
    >>> model.observe(Patch("black", (0, 0, 0)), 0.0, 30.0)
    >>> model.observe(Patch("white", (255, 255, 255)), 100.0, 3.0)
    >>> round(model.remaining_s([Patch("ramp-g", (0, 5, 0)), Patch("white", (255, 255, 255))]))
    24
    """

    def __init__(self):
        self._relative: list[float] = []
        self._durations: list[float] = []
        self._white_Lv: float | None = None
        self._full_drive_Lv: dict[int, float] = {}

    def channel_shares(self) -> np.ndarray:
        """Each channel's share of white luminance (measured where available)."""
        shares = np.array(PRIOR_CHANNEL_SHARES, dtype=float)
        if self._white_Lv:
            for channel, Lv in self._full_drive_Lv.items():
                shares[channel] = Lv / self._white_Lv
        return shares

    def expected_relative_luminance(self, patch: Patch) -> float:
        """Expected luminance of ``patch`` relative to white (for ranking only)."""
        drive = np.asarray(patch.rgb, dtype=float) / 255.0
        return float(self.channel_shares() @ drive ** RANKING_GAMMA)

    def observe(self, patch: Patch, Lv: float | None, duration_s: float) -> None:
        """Record that ``patch`` measured ``Lv`` cd/m² (``None`` if failed) in ``duration_s``."""
        if Lv is not None and np.isfinite(Lv):
            if patch.kind == "white":
                self._white_Lv = float(Lv)
            channel = _RAMP_CHANNEL.get(patch.kind)
            if channel is not None and patch.rgb[channel] == 255:
                self._full_drive_Lv[channel] = float(Lv)
        white = self._white_Lv or max(self._full_drive_Lv.values(), default=0.0)
        if Lv is not None and np.isfinite(Lv) and white > 0:
            relative = float(Lv) / white
        else:
            relative = self.expected_relative_luminance(patch)
        self._relative.append(max(relative, _DARKEST_RELATIVE))
        self._durations.append(float(duration_s))

    def patch_s(self, patch: Patch) -> float | None:
        """Expected seconds for ``patch``; ``None`` before anything was observed."""
        return self.remaining_s([patch])

    def remaining_s(self, patches) -> float | None:
        """Expected seconds for all ``patches``; ``None`` before anything was observed."""
        if not self._durations:
            return None
        # mean duration at each distinct observed luminance, interpolated in log luminance
        x, inverse = np.unique(np.log10(self._relative), return_inverse=True)
        mean_s = np.bincount(inverse, weights=self._durations) / np.bincount(inverse)
        targets = [self.expected_relative_luminance(p) for p in patches]
        return float(np.interp(np.log10(np.maximum(targets, _DARKEST_RELATIVE)), x, mean_s).sum())
