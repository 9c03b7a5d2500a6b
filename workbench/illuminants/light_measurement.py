"""Measure a light with the CS-2000 (or its emulator) and make a library source of it.

A spectroradiometer measures a light by its radiance off a white reference
tile lit by it (the usual lightbooth practice). :class:`SimulatedLightBooth`
is that set-up without hardware: a spectrally flat tile of reflectance
:data:`TILE_REFLECTANCE` under a source at a chosen illuminance, giving the
radiance ``L(λ) = ρ · E_e(λ) / π`` with ``E_e`` scaled so that
``683 lm/W · ∫ E_e ȳ dλ`` is the illuminance in lux. The emulator measures it
through the real driver on a pseudo-terminal (:func:`measure_light_simulated`),
exactly as a session measures the simulated headset; :func:`measure_light`
talks to a real instrument on a port. Either way the result is the
instrument's spectrum, normalized to 1 at 560 nm, as a ``measured`` source.
"""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np

from workbench.colorimetry import WORKING_WAVELENGTHS, observer_cmfs
from workbench.errors import InputError, WorkbenchError
from workbench.illuminants.source import Illuminant

__all__ = [
    "TILE_REFLECTANCE",
    "DEFAULT_ILLUMINANCE_LUX",
    "SimulatedLightBooth",
    "LightMeasurement",
    "measurement_to_illuminant",
    "measure_light",
    "measure_light_simulated",
]

TILE_REFLECTANCE = 0.99
"""Reflectance of the white reference tile (a pressed-PTFE-like standard)."""

DEFAULT_ILLUMINANCE_LUX = 1000.0
"""A bright lightbooth (ISO 3664 P2 viewing asks for 500 lx; P1 for 2000 lx)."""

_LM_PER_W = 683.0


@dataclass(frozen=True)
class SimulatedLightBooth:
    """A white tile lit by ``illuminant`` at ``illuminance_lux``, as the CS-2000 sees it."""

    illuminant: Illuminant
    illuminance_lux: float = DEFAULT_ILLUMINANCE_LUX
    tile_reflectance: float = TILE_REFLECTANCE

    def __post_init__(self):
        if not self.illuminance_lux > 0:
            raise InputError(f"illuminance {self.illuminance_lux!r} lx must be positive")
        if not 0 < self.tile_reflectance <= 1:
            raise InputError(f"tile reflectance {self.tile_reflectance!r} must be in (0, 1]")

    def radiance(self) -> np.ndarray:
        """Spectral radiance off the tile, W·sr⁻¹·m⁻²·nm⁻¹ at 380–780 nm, 1 nm (401 values)."""
        power = np.asarray(self.illuminant.sd.values, dtype=float)
        ybar = observer_cmfs("cie1931-2").values[:, 1]
        scale = self.illuminance_lux / (_LM_PER_W * float(power @ ybar))  # Δλ = 1 nm
        return self.tile_reflectance * scale * power / np.pi

    @property
    def luminance_cd_m2(self) -> float:
        """Luminance of the tile (cd/m²): ``ρ · E / π``."""
        return self.tile_reflectance * self.illuminance_lux / np.pi


@dataclass(frozen=True, eq=False)
class LightMeasurement:
    """A measured light and what the instrument said about it."""

    illuminant: Illuminant
    Lv: float
    xy: tuple[float, float]
    measurement_time_s: float
    instrument: str


def measurement_to_illuminant(radiance, name: str, description: str) -> Illuminant:
    """A ``measured`` source from a 380–780 nm radiance (NaN or negative noise clipped to 0)."""
    radiance = np.nan_to_num(np.asarray(radiance, dtype=float), nan=0.0)
    radiance = np.clip(radiance, 0.0, None)
    at_560 = radiance[WORKING_WAVELENGTHS == 560][0]
    if not at_560 > 0:
        raise WorkbenchError(f"the measured light {name!r} has no power at 560 nm; is the "
                             "instrument aimed at a lit white tile?")
    sd = colour.SpectralDistribution(radiance / at_560, WORKING_WAVELENGTHS, name=name)
    return Illuminant(id=f"measured:{name}", name=name, kind="measured", sd=sd,
                      description=description)


def _measure(port, name: str, what: str, progress=None, cancel=None) -> LightMeasurement:
    from instruments.cs2000 import CS2000

    with CS2000(port) as instrument:
        identity = instrument.identify()
        m = instrument.measure(progress=progress, cancel=cancel)
    label = f"{identity.model} #{identity.serial}"
    illuminant = measurement_to_illuminant(
        m.radiance, name, f"measured with the {label}: {what}; Lv {m.Lv:.4g} cd/m², "
        f"xy ({m.xy[0]:.4f}, {m.xy[1]:.4f})")
    return LightMeasurement(illuminant=illuminant, Lv=float(m.Lv),
                            xy=(float(m.xy[0]), float(m.xy[1])),
                            measurement_time_s=float(m.measurement_time_s), instrument=label)


def measure_light(port: str, name: str, progress=None, cancel=None) -> LightMeasurement:
    """Measure the light off a white tile with a CS-2000 on ``port`` (e.g. ``/dev/ttyACM0``)."""
    return _measure(port, name, f"a white tile on {port}", progress, cancel)


def measure_light_simulated(booth: SimulatedLightBooth, name: str | None = None, *,
                            time_scale: float = 0.0, seed: int | None = None, progress=None,
                            cancel=None) -> LightMeasurement:
    """Measure ``booth`` with the CS-2000 emulator through the real driver on a pseudo-terminal.

    ``time_scale`` is how long the emulator makes the driver wait, as a
    fraction of the real instrument's timing (0: no waiting).
    """
    from instruments.cs2000 import CS2000Emulator, serve_on_pty

    radiance = booth.radiance()
    emulator = CS2000Emulator(lambda: radiance, time_scale=time_scale, seed=seed)
    server = serve_on_pty(emulator)
    try:
        return _measure(server.port, name or f"{booth.illuminant.name} (measured)",
                        f"a simulated lightbooth, {booth.illuminant.name} at "
                        f"{booth.illuminance_lux:g} lx on a white tile", progress, cancel)
    finally:
        server.close()
