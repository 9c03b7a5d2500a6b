"""Calibration sessions of the simulated headset, generated directly (no serial protocol).

:func:`simulate_session` shows every patch of a measurement plan on a
:class:`~instruments.headset.SimulatedHeadset` and "measures" it the way the
CS-2000 emulator does (the same noise model, the same timing model for the
session clock), but vectorized and without the pseudo-terminal: a 214-patch
session takes ~1 s instead of minutes. ``measure --simulate`` is the
end-to-end path through the real driver; this is the generator for diagnostics
tests, benchmarks and demos, where hundreds of sessions with hidden effects
are needed.

Noise model: the emulator's own (:func:`instruments.cs2000.instrument_noise`):
per-wavelength multiplicative noise (0.2 %), an absolute floor, and a
whole-spectrum gain noise of ``repeatability`` per measurement (0.1 % by
default; the CS-2000's specified luminance repeatability is 0.15 % 2σ).
"""

from __future__ import annotations

import numpy as np

from instruments.cs2000 import instrument_noise
from instruments.headset import SimulatedHeadset, radiance_to_XYZ
from workbench.measurement.plans import MeasurementPlan, measurement_plan
from workbench.measurement.simulation import InstrumentTimingModel
from workbench.session import Session

__all__ = ["DEFAULT_REPEATABILITY", "simulate_session", "random_effect_magnitude"]

DEFAULT_REPEATABILITY = 0.001
"""Whole-spectrum relative noise of one measurement (the emulator's default)."""


def random_effect_magnitude(effect: str, rng: np.random.Generator) -> float:
    """A magnitude drawn uniformly from the headset effect's realistic range."""
    from instruments.headset import HEADSET_EFFECTS

    low, high = HEADSET_EFFECTS[effect].realistic_range
    return float(rng.uniform(low, high))


def simulate_session(effects: dict | None = None, seed: int = 0, *,
                     plan: MeasurementPlan | str = "paper", white_luminance: float = 100.0,
                     repeatability: float = DEFAULT_REPEATABILITY,
                     unit_seed: int | None = None, keep_spectra: bool = False) -> Session:
    """Measure a plan on the simulated headset with instrument noise.

    Parameters
    ----------
    effects : dict, optional
        Headset effects (id → magnitude), see :data:`instruments.headset.HEADSET_EFFECTS`.
    seed : int
        Seeds the plan's validation colours and the instrument noise.
    plan : MeasurementPlan or str
        A plan or a plan name (``"paper"``, ``"quick"``).
    unit_seed : int, optional
        Draws the headset unit from Table 1's spread (None: Table 1's means).
    keep_spectra : bool
        Keep the measured spectral radiance in the session.
    """
    if isinstance(plan, str):
        plan = measurement_plan(plan, seed)
    rgb = np.array([patch.rgb for patch in plan.patches], dtype=float)
    kinds = np.array([patch.kind for patch in plan.patches], dtype=object)
    # APL patches: a window of the field on a surround (full field on black otherwise)
    window = np.array([patch.window for patch in plan.patches], dtype=float)
    surround = np.array([patch.surround for patch in plan.patches], dtype=float)
    headset = SimulatedHeadset(effects, seed=unit_seed, white_luminance=white_luminance)
    # the session clock: each patch is measured after the previous one ended
    clean = headset.radiance(rgb, 0.0, window=window, surround=surround)
    timing = InstrumentTimingModel()
    durations = np.array([timing.measurement_s(spectrum) for spectrum in clean])
    t_end = np.cumsum(durations)
    headset.session_length_s = float(t_end[-1])
    spectra = np.stack([headset.radiance(rgb[i], float(t_end[i]), window=window[i],
                                         surround=surround[i]) for i in range(len(rgb))])
    rng = np.random.default_rng([seed, 7411])
    spectra = instrument_noise(spectra, rng, repeatability=repeatability)
    return Session(kind=kinds, rgb=rgb, XYZ=radiance_to_XYZ(spectra), t_s=t_end,
                   window=window, surround=surround,
                   wavelengths=headset.wavelengths if keep_spectra else None,
                   spectra=spectra if keep_spectra else None,
                   source=f"simulated: {headset.describe()}, plan {plan.name}, seed {seed}",
                   metadata={"effects": dict(headset.effects), "seed": seed})
