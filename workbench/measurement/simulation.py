"""Simulated sessions: the simulated headset measured by the CS-2000 emulator on a pty.

:func:`open_simulated_instrument` wires the pieces the way ``measure
--simulate`` uses them: a :class:`~instruments.headset.SimulatedHeadset`, a
:class:`~instruments.cs2000.CS2000Emulator` whose radiance source is what the
headset shows, served on a pseudo-terminal (:func:`~instruments.cs2000.serve_on_pty`)
so that the real :class:`~instruments.cs2000.CS2000` driver talks to it.

Time in a simulated session is the **instrument's modelled time**, whatever
the emulator's ``time_scale`` (which only sets how long the pty makes the
host wait): each time the emulator starts a measurement, the
:class:`ModelledSessionClock` advances by the pre-measurement plus the
measurement time that the emulator's timing model gives for the radiance being
measured (:class:`InstrumentTimingModel`, which asks the emulator's pure
:func:`~instruments.cs2000.measurement_timing`). The headset's warm-up and the
journal's ``t_s`` both read that clock, so a run at ``--time-scale 0``
produces the same session timeline as one at real timing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from instruments.cs2000 import CS2000Emulator, measurement_timing, radiance_to_luminance, serve_on_pty
from instruments.cs2000.emulator import LUMINANCE_RANGE_CD_M2
from instruments.cs2000.protocol import WAVELENGTHS_NM
from instruments.headset import SimulatedHeadset
from workbench.measurement.plans import MeasurementPlan

__all__ = [
    "InstrumentTimingModel",
    "ModelledSessionClock",
    "SimulatedInstrument",
    "open_simulated_instrument",
    "modelled_plan_duration_s",
]


class InstrumentTimingModel:
    """Seconds a CS-2000 takes to measure a radiance, from the emulator's timing model.

    The emulator's own pure functions give the luminance it sees
    (:func:`~instruments.cs2000.radiance_to_luminance`) and its timing
    (:func:`~instruments.cs2000.measurement_timing`) in normal speed mode with
    the internal ND filter on auto, the emulator's defaults. Nothing waits.

    Parameters
    ----------
    angle : int
        Measuring-angle code (0 = 1°, 1 = 0.2°, 2 = 0.1°), as the emulator measured.
    speed_mode : int
        0 normal (up to 242 s in the dark, the default) or 1 fast (up to 16 s), as set on the
        instrument (``SPMS``): another dark end, where every patch costs about the same.
    """

    def __init__(self, angle: int = 0, speed_mode: int = 0):
        if angle not in LUMINANCE_RANGE_CD_M2:
            raise ValueError(f"angle must be 0 (1°), 1 (0.2°) or 2 (0.1°), got {angle!r}")
        if speed_mode not in (0, 1):
            raise ValueError(f"speed_mode must be 0 (normal) or 1 (fast), got {speed_mode!r}")
        self.angle = angle
        self.speed_mode = speed_mode

    def measurement_s(self, radiance: np.ndarray) -> float:
        """Pre-measurement plus measurement time (s) at real timing for ``radiance`` (401,).

        Raises
        ------
        ValueError
            If the emulator would refuse the radiance: not 401 finite values
            (ER99), or brighter than the instrument's range even with the
            internal ND filter (ER10).
        """
        radiance = np.asarray(radiance, dtype=float)
        if radiance.shape != (len(WAVELENGTHS_NM),) or not np.all(np.isfinite(radiance)):
            raise ValueError(f"the radiance must be {len(WAVELENGTHS_NM)} finite values (380..780 nm), "
                             f"got shape {radiance.shape}")
        luminance = radiance_to_luminance(radiance)
        maximum = LUMINANCE_RANGE_CD_M2[self.angle][1]
        if luminance > maximum:
            raise ValueError(f"the emulator refuses {luminance:.4g} cd/m² (ER10): it is outside the "
                             f"instrument's range (at most {maximum:g} cd/m² with the internal ND filter)")
        return measurement_timing(luminance, mode=self.speed_mode, angle=self.angle).duration_s


class ModelledSessionClock:
    """Session clock of a simulated session: advanced by each modelled measurement.

    Parameters
    ----------
    offset_s : float
        Session time at which this clock starts (where a resumed session left off).
    """

    def __init__(self, offset_s: float = 0.0):
        self._now = float(offset_s)

    def now(self) -> float:
        return self._now

    def advance(self, seconds: float) -> None:
        self._now += float(seconds)


@dataclass
class SimulatedInstrument:
    """A simulated headset and the emulated CS-2000 measuring it over a pty.

    Attributes
    ----------
    headset : SimulatedHeadset
    emulator : CS2000Emulator
    server : PtyServer
        Open ``server.port`` with :class:`~instruments.cs2000.CS2000`.
    clock : ModelledSessionClock
    """

    headset: SimulatedHeadset
    emulator: CS2000Emulator
    server: object
    clock: ModelledSessionClock

    def close(self) -> None:
        self.server.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def open_simulated_instrument(
    effects: dict | None = None,
    *,
    seed: int | None = None,
    headset_seed: int | None = None,
    time_scale: float = 0.0,
    faults: Sequence = (),
    clock_offset_s: float = 0.0,
    plan: MeasurementPlan | None = None,
    session_length_s: float | None = None,
    white_luminance: float = 100.0,
) -> SimulatedInstrument:
    """Build the simulated headset, the CS-2000 emulator measuring it, and serve it on a pty.

    Parameters
    ----------
    effects : dict, optional
        Headset effects (see :data:`instruments.headset.HEADSET_EFFECTS`).
    seed : int, optional
        Seeds the instrument noise.
    headset_seed : int, optional
        Draws the headset unit from Table 1's spread; ``None``: Table 1's means.
    time_scale : float
        How long the emulator makes the host wait, as a fraction of real timing.
    faults : sequence
        Emulator faults to inject.
    clock_offset_s : float
        Session time to start the modelled clock at (resume).
    plan : MeasurementPlan, optional
        The plan to be measured: with ``temporal-drift`` on and no
        ``session_length_s``, its modelled duration sets the warm-up time constant.
    session_length_s : float, optional
        Expected session length (s), which sets the headset's warm-up time
        constant (see :data:`instruments.headset.WARMUP_TAU_FRACTION`).
    white_luminance : float
        Headset white, cd/m².

    Returns
    -------
    SimulatedInstrument
    """
    clock = ModelledSessionClock(clock_offset_s)
    headset = SimulatedHeadset(effects, seed=headset_seed, white_luminance=white_luminance, clock=clock.now)
    timing = InstrumentTimingModel()
    if session_length_s is None and plan is not None and "temporal-drift" in headset.effects:
        session_length_s = modelled_plan_duration_s(plan, headset, timing)
    if session_length_s is not None:
        headset.session_length_s = float(session_length_s)

    def radiance_source() -> np.ndarray:
        radiance = headset.current_radiance()
        clock.advance(timing.measurement_s(radiance))
        return radiance

    emulator = CS2000Emulator(radiance_source, time_scale=time_scale, seed=seed, faults=faults)
    return SimulatedInstrument(headset, emulator, serve_on_pty(emulator), clock)


def modelled_plan_duration_s(plan: MeasurementPlan, headset: SimulatedHeadset,
                             timing: InstrumentTimingModel | None = None) -> float:
    """Seconds the instrument would take to measure every patch of ``plan`` on ``headset``.

    Sums :meth:`InstrumentTimingModel.measurement_s` over the patches, each at the
    start of the session (warm-up ignored); data transfer is not included.
    """
    timing = timing or InstrumentTimingModel()
    radiances = headset.radiance(np.array([p.rgb for p in plan.patches], dtype=float))
    return float(sum(timing.measurement_s(r) for r in radiances))
