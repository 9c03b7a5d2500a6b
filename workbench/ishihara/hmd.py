"""The simulated HMD the virtual test runs on, calibrated and measured through the CS-2000.

:class:`HeadsetRig` wires the instruments the way a real session does: a
:class:`~instruments.headset.SimulatedHeadset` (the paper's HTC Vive, Table 1),
a :class:`~instruments.cs2000.CS2000Emulator` measuring what the headset shows,
served on a pseudo-terminal (:func:`~instruments.cs2000.serve_on_pty`), and the
real :class:`~instruments.cs2000.CS2000` driver talking to it. Its
:meth:`HeadsetRig.calibrate` measures a calibration plan (the paper's by
default: black, white, channel sweeps in steps of 5, validation colours) and
fits the paper's display model to it; :meth:`HeadsetRig.measure` measures any
DAC triplet end to end.

:func:`calibrated_headset` runs that calibration once per seed and keeps the
result (headset + fitted display model) for the simulated observers, which
look at the headset's spectral radiance directly.

Scale: DAC values 0..255; XYZ absolute (cd/m²), as the CS-2000 reports them.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from instruments.cs2000 import CS2000, CS2000Emulator, serve_on_pty
from instruments.headset import SimulatedHeadset
from workbench.display import DisplayModel, fit_display_model
from workbench.measurement.plans import measurement_plan
from workbench.session import Session

__all__ = [
    "DEFAULT_HEADSET_SEED",
    "CalibratedHeadset",
    "HeadsetRig",
    "calibrated_headset",
]

DEFAULT_HEADSET_SEED = 5658
"""Seed of the simulated headset unit and of the instrument noise (the paper's article number)."""


@dataclass(frozen=True, eq=False)
class CalibratedHeadset:
    """A simulated headset and the display model fitted to its measured calibration.

    Attributes
    ----------
    headset : SimulatedHeadset
        Emits spectral radiance for DAC values (``headset.radiance(rgb)``).
    display : DisplayModel
        Fitted to :attr:`session` (the paper's gamma-matrix model).
    session : Session
        The calibration as the CS-2000 measured it.
    seed : int
    """

    headset: SimulatedHeadset
    display: DisplayModel
    session: Session
    seed: int

    def radiance(self, rgb_dac) -> np.ndarray:
        """Spectral radiance ``(…, 401)`` the headset emits for DAC values ``(…, 3)``."""
        rgb = np.asarray(rgb_dac, dtype=float)
        return self.headset.radiance(rgb.reshape(-1, 3)).reshape(rgb.shape[:-1] + (-1,))


class HeadsetRig:
    """Simulated headset + CS-2000 emulator on a pty + the real driver; a context manager.

    Parameters
    ----------
    seed : int
        Seeds the headset unit (drawn from Table 1's spread) and the instrument noise.
    effects : dict, optional
        Headset effects (:data:`instruments.headset.HEADSET_EFFECTS`); none by default.
    white_luminance : float
        Headset white, cd/m².
    """

    def __init__(self, seed: int = DEFAULT_HEADSET_SEED, effects: dict | None = None,
                 white_luminance: float = 100.0):
        self.seed = int(seed)
        self.headset = SimulatedHeadset(effects, seed=self.seed, white_luminance=white_luminance)
        self._emulator = CS2000Emulator(radiance_source=self.headset.current_radiance,
                                        time_scale=0, seed=self.seed)
        self._server = None
        self._meter = None

    def __enter__(self) -> "HeadsetRig":
        self._server = serve_on_pty(self._emulator)
        try:
            self._meter = CS2000(self._server.port).__enter__()
        except BaseException:
            self._server.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        try:
            if self._meter is not None:
                self._meter.__exit__(*exc)
        finally:
            self._meter = None
            if self._server is not None:
                self._server.close()
            self._server = None

    def measure(self, rgb_dac):
        """Show ``rgb_dac`` (3,) full field and measure it; a CS-2000 ``Measurement``."""
        if self._meter is None:
            raise RuntimeError("HeadsetRig.measure needs the rig open: use 'with HeadsetRig() as rig'")
        self.headset.show(np.asarray(rgb_dac, dtype=float))
        return self._meter.measure()

    def calibrate(self, plan: str = "paper") -> CalibratedHeadset:
        """Measure calibration ``plan`` (``"paper"`` or ``"quick"``) and fit the paper's model."""
        patches = measurement_plan(plan, self.seed).patches
        measurements = [self.measure(p.rgb) for p in patches]
        session = Session(kind=[p.kind for p in patches], rgb=[p.rgb for p in patches],
                          XYZ=[m.XYZ for m in measurements],
                          wavelengths=measurements[0].wavelengths,
                          spectra=[m.radiance for m in measurements],
                          source=f"{self.headset.describe()}, measured by the CS-2000 emulator "
                                 f"({plan} plan)")
        return CalibratedHeadset(self.headset, fit_display_model(session, "gamma-matrix"),
                                 session, self.seed)


@lru_cache(maxsize=4)
def calibrated_headset(seed: int = DEFAULT_HEADSET_SEED, plan: str = "paper") -> CalibratedHeadset:
    """The simulated headset with its display model fitted to a measured calibration (cached)."""
    with HeadsetRig(seed) as rig:
        return rig.calibrate(plan)
