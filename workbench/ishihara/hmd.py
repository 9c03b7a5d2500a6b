"""The simulated HMD the virtual test runs on, calibrated and measured through the CS-2000.

:class:`HeadsetRig` wires the instruments the way a real session does: a
:class:`~instruments.headset.SimulatedHeadset` (the paper's HTC Vive, Table 1),
a :class:`~instruments.cs2000.CS2000Emulator` measuring what the headset shows,
served on a pseudo-terminal (:func:`~instruments.cs2000.serve_on_pty`), and the
real :class:`~instruments.cs2000.CS2000` driver talking to it. Its
:meth:`HeadsetRig.calibrate` measures a calibration plan (the paper's by
default: black, white, channel sweeps in steps of 5, validation colours) and
diagnoses it (:func:`workbench.diagnostics.diagnose`): the paper's
gamma-matrix model is the *baseline*, and the model extended with what the
diagnosis found is the one the workbench uses (:attr:`CalibratedHeadset.display`).
:meth:`HeadsetRig.measure` measures any DAC triplet end to end.

The headset is realistic by default (:data:`REALISTIC_HEADSET_EFFECTS`): it
emits Table 1's black and loses a little light to OLED power limiting, so the
baseline model is wrong in the ways a real HMD makes it wrong, and the
diagnosis has something to find. A clean headset (no effects) is exactly the
baseline model, and any figure measured on it is only instrument noise and
quantisation.

:func:`calibrated_headset` runs that calibration once per process for each
(seed, plan, effects) and keeps the result (headset + models + diagnosis) for
Table 5, which measures the same headset again through a fresh rig, and for
the simulated observers, which look at the headset's spectral radiance
directly.

Scale: DAC values 0..255; XYZ absolute (cd/m²), as the CS-2000 reports them.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from instruments.cs2000 import CS2000, CS2000Emulator, serve_on_pty
from instruments.headset import SimulatedHeadset
from workbench.diagnostics import Diagnosis, diagnose
from workbench.display import DisplayModel
from workbench.measurement.plans import measurement_plan
from workbench.session import Session

__all__ = [
    "DEFAULT_HEADSET_SEED",
    "REALISTIC_HEADSET_EFFECTS",
    "CalibratedHeadset",
    "HeadsetRig",
    "calibrated_headset",
]

DEFAULT_HEADSET_SEED = 5658
"""Seed of the simulated headset unit and of the instrument noise (the paper's article number)."""

REALISTIC_HEADSET_EFFECTS = (("black-offset", 0.004), ("channel-interaction", 0.05))
"""Effects of the default rig, ``(effect id, magnitude)`` pairs.

``black-offset`` 0.004: the black of the paper's Table 1 (0.4 % of white, the
simulator's default); ``channel-interaction`` 0.05: full white 5 % short of
R + G + B (OLED power limiting, the low end of the realistic 5–15 %).
"""


@dataclass(frozen=True, eq=False)
class CalibratedHeadset:
    """A simulated headset, its measured calibration and the display models fitted to it.

    Attributes
    ----------
    headset : SimulatedHeadset
        Emits spectral radiance for DAC values (``headset.radiance(rgb)``).
    display : DisplayModel
        The model the workbench uses: :attr:`diagnosis`'s extended model (the
        baseline itself when nothing was found).
    baseline : DisplayModel
        The paper's gamma-matrix model (Eq. 1–2), fitted to the same session.
    diagnosis : Diagnosis
        What :func:`workbench.diagnostics.diagnose` found in :attr:`session`.
    session : Session
        The calibration as the CS-2000 measured it.
    seed : int
    plan : str
        The calibration plan measured.
    """

    headset: SimulatedHeadset
    display: DisplayModel
    baseline: DisplayModel
    diagnosis: Diagnosis
    session: Session
    seed: int
    plan: str = "paper"

    @property
    def findings(self) -> tuple:
        """Effect ids the diagnosis found, most important first."""
        return tuple(r.effect for r in self.diagnosis.findings)

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
    effects : dict or sequence of (str, float), optional
        Headset effects (:data:`instruments.headset.HEADSET_EFFECTS`); none by
        default (a clean headset: :data:`REALISTIC_HEADSET_EFFECTS` is what
        :func:`calibrated_headset` uses).
    white_luminance : float
        Headset white, cd/m².
    headset : SimulatedHeadset, optional
        Measure this headset (e.g. a calibrated one again) instead of building
        one from ``seed``, ``effects`` and ``white_luminance``.
    noise_seed : int, optional
        Seed of the instrument noise (default ``seed``).
    """

    def __init__(self, seed: int = DEFAULT_HEADSET_SEED, effects=None,
                 white_luminance: float = 100.0, *, headset: SimulatedHeadset | None = None,
                 noise_seed: int | None = None):
        self.seed = int(seed)
        if headset is None:
            headset = SimulatedHeadset(dict(effects or {}), seed=self.seed,
                                       white_luminance=white_luminance)
        self.headset = headset
        self._emulator = CS2000Emulator(radiance_source=self.headset.current_radiance,
                                        time_scale=0,
                                        seed=self.seed if noise_seed is None else int(noise_seed))
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
        """Measure calibration ``plan`` (``"paper"`` or ``"quick"``) and diagnose it.

        Returns the headset with the paper's model (baseline) and the model
        extended with the effects the diagnosis found (:attr:`CalibratedHeadset.display`).
        """
        patches = measurement_plan(plan, self.seed).patches
        measurements = [self.measure(p.rgb) for p in patches]
        session = Session(kind=[p.kind for p in patches], rgb=[p.rgb for p in patches],
                          XYZ=[m.XYZ for m in measurements],
                          wavelengths=measurements[0].wavelengths,
                          spectra=[m.radiance for m in measurements],
                          source=f"{self.headset.describe()}, measured by the CS-2000 emulator "
                                 f"({plan} plan)")
        diagnosis = diagnose(session)
        return CalibratedHeadset(headset=self.headset, display=diagnosis.extended,
                                 baseline=diagnosis.baseline, diagnosis=diagnosis,
                                 session=session, seed=self.seed, plan=plan)


def _effects_key(effects) -> tuple:
    pairs = effects.items() if isinstance(effects, dict) else (effects or ())
    return tuple(sorted((str(k), float(v)) for k, v in pairs))


@lru_cache(maxsize=4)
def _calibrated(seed: int, plan: str, effects: tuple) -> CalibratedHeadset:
    with HeadsetRig(seed, dict(effects)) as rig:
        return rig.calibrate(plan)


def calibrated_headset(seed: int = DEFAULT_HEADSET_SEED, plan: str = "paper",
                       effects=REALISTIC_HEADSET_EFFECTS) -> CalibratedHeadset:
    """The simulated headset calibrated through the CS-2000 emulator and diagnosed (cached).

    Parameters
    ----------
    seed : int
        Headset unit and instrument noise.
    plan : str
        Calibration plan (``"paper"``: 214 patches, ~1.5 s with the emulator at no wait).
    effects : dict or sequence of (str, float)
        Headset effects; default :data:`REALISTIC_HEADSET_EFFECTS`, ``()`` for
        a clean headset.
    """
    return _calibrated(int(seed), str(plan), _effects_key(effects))
