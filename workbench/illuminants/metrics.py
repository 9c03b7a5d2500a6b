"""Metrics of a light source: CIE Rf and Rg, CCT and Duv, chromaticity, the
level-1 light colour, and how adequate level 1 is under it.

- Rf: CIE 224:2017 (colour-science ``colour_fidelity_index(method="CIE 2017")``).
- Rg: the gamut index of ANSI/IES TM-30-18, which uses the same 99 samples and
  reference illuminant as CIE 224:2017 (CIE 224 itself defines no Rg).
- CCT, Duv: Ohno (2013), on the CIE 1931 2° chromaticity of the native spectrum
  (360–830 nm where the source has data), as CCT is defined.
- ``XYZ``, ``xy``: of the perfect diffuser at ``k · Y_white`` with the chosen observer.
  The light colours and the level-1 errors always use the display's own
  observer (CIE 1931 2°: the CS-2000's XYZ and sRGB are defined for it), so
  the choice of a 10° observer never mixes observers.
- ``rgb8``: ``display_inverse(XYZ_t(ρ=1))`` for the ideal sRGB display and for a profile.
- Level-1 adequacy (a question the paper leaves open: "setting a CFI
  reference value requires further research"): CIEDE2000 between what level 1
  shows and ``XYZ_t`` on the ColorChecker and on the 99 CIE 2017 colour
  evaluation samples, each texture being its exact sRGB under D65 (perfectly
  authored, 8-bit), in CIELAB relative to ``XYZ_t`` of the perfect diffuser
  under the source.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache

import colour
import numpy as np

from workbench.colorimetry import (
    DEFAULT_K,
    DEFAULT_OBSERVER,
    delta_E2000,
    reflectances_to_XYZ_relative,
    white_XYZ_relative,
)
from workbench.colour_management import authored_srgb8, engine_render, light_colour
from workbench.display import DisplayModel, SRGBDisplay
from workbench.illuminants.source import Illuminant
from workbench.samples import SAMPLE_SETS, sample_set

__all__ = [
    "Level1Adequacy",
    "IlluminantMetrics",
    "fidelity_Rf_Rg",
    "CCT_Duv",
    "level1_adequacy",
    "illuminant_metrics",
]


@dataclass(frozen=True)
class Level1Adequacy:
    """CIEDE2000 that level 1 causes on one sample set under one source."""

    sample_set: str
    n: int
    mean_dE00: float
    p95_dE00: float
    max_dE00: float
    worst_sample: str


@dataclass(frozen=True)
class IlluminantMetrics:
    """Everything the library shows about one source."""

    id: str
    name: str
    kind: str
    xy: tuple[float, float]
    XYZ: tuple[float, float, float]
    CCT: float
    Duv: float
    Rf: float
    Rg: float
    rgb8_srgb: tuple[int, int, int]
    rgb8_display: tuple[int, int, int]
    display: str
    light_in_gamut: bool
    level1: tuple[Level1Adequacy, ...]
    k: float
    observer: str

    @property
    def level1_mean_dE00(self) -> float:
        """Mean CIEDE2000 over all samples of all sets."""
        total = sum(a.n for a in self.level1)
        return sum(a.mean_dE00 * a.n for a in self.level1) / total

    @property
    def level1_max_dE00(self) -> float:
        return max(a.max_dE00 for a in self.level1)

    def to_json(self) -> dict:
        """The CLI's ``illuminants show --json`` record."""
        return {
            "id": self.id,
            "name": self.name,
            "kind": self.kind,
            "xy": list(self.xy),
            "XYZ": list(self.XYZ),
            "CCT": self.CCT,
            "Duv": self.Duv,
            "Rf": self.Rf,
            "Rg": self.Rg,
            "rgb8_srgb": list(self.rgb8_srgb),
            "rgb8_display": list(self.rgb8_display),
            "display": self.display,
            "light_in_gamut": self.light_in_gamut,
            "level1_dE00": {
                "mean": self.level1_mean_dE00,
                "max": self.level1_max_dE00,
                "sets": {a.sample_set: {k: v for k, v in asdict(a).items() if k != "sample_set"}
                         for a in self.level1},
                "reference_white": "XYZ_t of the perfect diffuser under this source",
            },
            "k": self.k,
            "observer": self.observer,
        }


def _key(sd: colour.SpectralDistribution) -> bytes:
    return np.asarray(sd.values, dtype=float).tobytes()


@lru_cache(maxsize=256)
def _fidelity_cached(key: bytes, wavelengths: bytes) -> tuple[float, float]:
    values = np.frombuffer(key)
    sd = colour.SpectralDistribution(values, np.frombuffer(wavelengths))
    cfi = colour.colour_fidelity_index(sd, method="CIE 2017")
    tm30 = colour.colour_fidelity_index(sd, additional_data=True, method="ANSI/IES TM-30-18")
    return float(cfi), float(tm30.R_g)


def fidelity_Rf_Rg(illuminant: Illuminant) -> tuple[float, float]:
    """CIE 2017 Rf and TM-30-18 Rg of a source (cached per spectrum)."""
    return _fidelity_cached(_key(illuminant.sd), np.asarray(illuminant.sd.wavelengths,
                                                            dtype=float).tobytes())


def CCT_Duv(illuminant: Illuminant) -> tuple[float, float]:
    """Correlated colour temperature (K) and Duv, Ohno (2013), CIE 1931 2°.

    Computed from the source's native spectrum with colour-science's default
    integration (ASTM E308, CMFs over 360–830 nm), as CIE 015 defines them.
    """
    xy = colour.XYZ_to_xy(colour.sd_to_XYZ(illuminant.native_sd))
    CCT, Duv = colour.uv_to_CCT(colour.xy_to_UCS_uv(xy), method="Ohno 2013")
    return float(CCT), float(Duv)


def level1_adequacy(illuminant: Illuminant, display: DisplayModel | None = None, *,
                    k: float = DEFAULT_K, observer: str = DEFAULT_OBSERVER,
                    sets: tuple[str, ...] = tuple(SAMPLE_SETS)) -> tuple[Level1Adequacy, ...]:
    """CIEDE2000 that level-1 colour management leaves under ``illuminant`` (module doc)."""
    display = display or SRGBDisplay()
    light = light_colour(illuminant.sd, display, k=k, observer=observer)
    Y_white = float(display.white_XYZ[1])  # observer checked by light_colour
    results = []
    for name in sets:
        samples = sample_set(name)
        texture = authored_srgb8(samples.reflectances)
        shown = display.forward(engine_render(texture, light.rgb8))
        target = reflectances_to_XYZ_relative(samples.reflectances, illuminant.sd, observer,
                                              k=k, Y_white=Y_white)
        dE = delta_E2000(shown, target, light.XYZ)
        results.append(Level1Adequacy(
            sample_set=name, n=len(dE), mean_dE00=float(dE.mean()),
            p95_dE00=float(np.percentile(dE, 95)), max_dE00=float(dE.max()),
            worst_sample=samples.names[int(np.argmax(dE))]))
    return tuple(results)


def illuminant_metrics(illuminant: Illuminant, display: DisplayModel | None = None, *,
                       k: float = DEFAULT_K, observer: str = DEFAULT_OBSERVER
                       ) -> IlluminantMetrics:
    """All metrics of ``illuminant``; ``display`` defaults to the ideal sRGB display."""
    display = display or SRGBDisplay()
    srgb = SRGBDisplay()
    srgb_light = light_colour(illuminant.sd, srgb, k=k, observer=srgb.observer)
    light = light_colour(illuminant.sd, display, k=k, observer=display.observer)
    XYZ = white_XYZ_relative(illuminant.sd, observer, k=k, Y_white=float(display.white_XYZ[1]))
    Rf, Rg = fidelity_Rf_Rg(illuminant)
    CCT, Duv = CCT_Duv(illuminant)
    return IlluminantMetrics(
        id=illuminant.id, name=illuminant.name, kind=illuminant.kind,
        xy=tuple(float(v) for v in colour.XYZ_to_xy(XYZ)),
        XYZ=tuple(float(v) for v in XYZ),
        CCT=CCT, Duv=Duv, Rf=Rf, Rg=Rg,
        rgb8_srgb=tuple(int(v) for v in srgb_light.rgb8),
        rgb8_display=tuple(int(v) for v in light.rgb8),
        display=display.describe(), light_in_gamut=light.in_gamut,
        level1=level1_adequacy(illuminant, display, k=k, observer=display.observer),
        k=k, observer=observer,
    )
