"""The simulated headset: spectral radiance of an OLED HMD, with optional physical effects.

The headset models the HTC Vive measured in Díaz-Barrancas et al. (2020): three
narrow-band OLED primaries shaped like the paper's Fig. 3, tuned so that their
CIE 1931 chromaticities are those of its Table 1, with the channel luminances
solved so that full white has Table 1's white chromaticity and the requested
luminance, and per-channel power-law tone curves with Table 1's gammas. A clean
headset is additive (white = R + G + B) and emits nothing at DAC 0.

Physical effects from the diagnostics vocabulary (``design.md`` §5) can be
switched on, each with a magnitude; :data:`HEADSET_EFFECTS` documents each one's
meaning, realistic range and default:

``black-offset``
    Flare and leakage at DAC 0: a constant spectrum with Table 1's black
    chromaticity, its luminance ``magnitude × white luminance``.
``channel-interaction``
    OLED power limiting: once the load (mean linear drive of the three
    channels) exceeds that of one channel at full drive, the whole output is
    scaled down, linearly in the load, reaching ``1 − magnitude`` at full white.
    Single-channel ramps are therefore untouched and white measures
    ``1 − magnitude`` of R + G + B.
``chromaticity-shift``
    Each primary's chromaticity moves toward white at low drive: at drive ``d``
    a fraction ``β₀ (1 − d)²`` of the channel's luminance is emitted with the
    white's spectrum; ``β₀`` is solved per channel so that the xy distance from
    the full-drive primary tends to ``magnitude`` as ``d → 0``. Luminance is
    unchanged and the shift vanishes at full drive.
``tone-curve-shape``
    Black crush: DAC levels below ``magnitude × 255`` emit nothing, and above
    it the power law is re-stretched, ``((d − d₀)/(1 − d₀))^γ``.
``temporal-drift``
    Warm-up: the whole output is multiplied by ``1 − magnitude · exp(−t/τ)``
    with ``τ = WARMUP_TAU_FRACTION × session_length_s``.
``apl-dependence``
    Automatic brightness limiting: the output is scaled by a function of the
    frame's load ``L = Σ_c p_c (w·lin_c(patch) + (1 − w)·lin_c(surround))``
    (``w`` the patch window's fraction of the field, ``lin_c`` the channel's
    tone curve, ``p_c`` the channel's share of the panel's drive current at
    full white, from the channel luminances and
    :data:`OLED_CURRENT_EFFICIENCY_CD_PER_A`): 1 up to the knee
    :data:`APL_KNEE_LOAD`, then ``(knee / L)^a`` with ``a`` solved so that a
    full-field white loses ``magnitude``. The limiter follows a change of
    frame with the time constant :data:`APL_TIME_CONSTANT_S`; the instrument
    reads at least :data:`APL_READ_DELAY_S` after the frame changed. Unlike
    ``channel-interaction`` (which depends on the patch's own drive), it
    depends on the whole frame, so it shows only when patches are measured
    as windows or on surrounds.

    Grounding (``../shared/data/real/oled-apl/``): a Dell AW3225QF QD-OLED
    (Desktop preset) holds its white up to a 10 % window, shows 85 % of it in
    a 20 % window and 56 % full field (loss 0.44; 0.76 in its HDR peak
    preset); a Samsung OLED's white target loses 21 % as the surround goes
    from 0 to 0.9 and 32 % with a large white square beside it too. Held on
    screen, the AW3225QF's full white stays within 1 % from its first
    reading, 6 s after onset, to 70 s: the limiter settles well within a
    second, as OLED limiters that act within a few frames do.

Units: wavelengths in nm (380–780, 1 nm); spectral radiance in
W·sr⁻¹·m⁻²·nm⁻¹; luminance in cd/m² (``K_m = 683 lm/W`` times the integral
against the CIE 1931 ȳ); DAC values are floats on 0..255; times in seconds.

References
----------
Díaz-Barrancas, F., Cwierz, H., Pardo, P. J., Pérez, Á. L., Suero, M. I.
(2020). Spectral Color Management in Virtual Reality Scenes. *Sensors*, 20(19),
5658. Table 1 and Fig. 3.
"""

from __future__ import annotations

import functools
import logging
import math
import time
from dataclasses import dataclass
from typing import Callable

import colour
import numpy as np
from scipy.optimize import brentq, least_squares

__all__ = [
    "WAVELENGTHS_NM",
    "TABLE1_HTC_VIVE",
    "HeadsetCharacteristics",
    "HeadsetEffectSpec",
    "HEADSET_EFFECTS",
    "HeadsetError",
    "WARMUP_TAU_FRACTION",
    "APL_KNEE_LOAD",
    "APL_TIME_CONSTANT_S",
    "APL_READ_DELAY_S",
    "OLED_CURRENT_EFFICIENCY_CD_PER_A",
    "PrimaryShape",
    "parse_effect",
    "radiance_to_XYZ",
    "validate_effects",
    "SimulatedHeadset",
]

_LOG = logging.getLogger(__name__)

WAVELENGTHS_NM = np.arange(380.0, 781.0, 1.0)
"""Wavelengths (nm) of every spectrum the headset emits: 380–780 nm at 1 nm."""

_CHANNELS = ("r", "g", "b")
_N_CHANNELS = len(_CHANNELS)
_FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))
_HC_EV_NM = 1239.841984  # h·c in eV·nm: converts a vibronic energy step to a wavelength
_VIBRONIC_STEP_EV = 0.17  # spacing of the 0-0 and 0-1 vibronic bands of organic emitters
_SHOULDER_WIDTH_FACTOR = 1.2  # the 0-1 band is a little broader than the 0-0 band

WARMUP_TAU_FRACTION = 0.25
"""Warm-up time constant of ``temporal-drift`` as a fraction of the session length."""

APL_KNEE_LOAD = 0.15
"""Frame load (full-field white = 1) up to which ``apl-dependence`` leaves the output alone."""

APL_TIME_CONSTANT_S = 0.2
"""Time constant (s) with which the ``apl-dependence`` limiter follows a change of frame."""

APL_READ_DELAY_S = 1.0
"""Seconds between a frame change and the instrument's reading at the earliest (the
CS-2000's shortest pre-measurement)."""

OLED_CURRENT_EFFICIENCY_CD_PER_A = {"r": 30.0, "g": 80.0, "b": 8.0}
"""Typical current efficiencies of red and green phosphorescent and blue fluorescent
OLED emitters (cd/A); they weight each channel's share of the panel's load."""


@dataclass(frozen=True)
class HeadsetCharacteristics:
    """What a colorimetric characterization reports about a headset (Table 1).

    Attributes
    ----------
    primaries_xy : dict of str to (float, float)
        CIE 1931 chromaticity of the full-drive red, green and blue channels.
    white_xy : (float, float)
        Chromaticity of full white.
    black_xy : (float, float)
        Chromaticity of the light emitted at DAC 0.
    gammas : dict of str to float
        Exponent of each channel's power-law tone curve.
    primaries_xy_sd, white_xy_sd, black_xy_sd
        Standard deviations of those chromaticities (unit-to-unit spread).
    """

    primaries_xy: dict
    white_xy: tuple
    black_xy: tuple
    gammas: dict
    primaries_xy_sd: dict
    white_xy_sd: tuple
    black_xy_sd: tuple


TABLE1_HTC_VIVE = HeadsetCharacteristics(
    primaries_xy={"r": (0.667, 0.332), "g": (0.217, 0.710), "b": (0.139, 0.051)},
    white_xy=(0.299, 0.315),
    black_xy=(0.311, 0.307),
    gammas={"r": 2.43, "g": 2.38, "b": 2.38},
    primaries_xy_sd={"r": (0.004, 0.003), "g": (0.007, 0.002), "b": (0.002, 0.002)},
    white_xy_sd=(0.002, 0.002),
    black_xy_sd=(0.01, 0.004),
)
"""The HTC Vive of Díaz-Barrancas et al. (2020), Table 1."""


@dataclass(frozen=True)
class PrimaryShape:
    """Spectral shape of one OLED primary: a skewed peak plus its vibronic shoulder.

    Attributes
    ----------
    peak_nm : float
        Wavelength of the main (0-0) emission band.
    fwhm_nm : float
        Full width at half maximum of the main band (before skew).
    skew : float
        Asymmetry of the main band, -1..1: the short-wavelength side has width
        ``σ(1 − skew)``, the long-wavelength side ``σ(1 + skew)``.
    shoulder : float
        Relative amplitude of the 0-1 vibronic band, 0.17 eV below the peak.
    """

    peak_nm: float
    fwhm_nm: float
    skew: float
    shoulder: float

    def spectrum(self, wavelengths: np.ndarray) -> np.ndarray:
        """Relative spectral power at ``wavelengths`` (nm), peak of the main band = 1."""
        sigma = self.fwhm_nm / _FWHM_PER_SIGMA
        main = _split_gaussian(wavelengths, self.peak_nm, sigma * (1 - self.skew), sigma * (1 + self.skew))
        shoulder_nm = _HC_EV_NM / (_HC_EV_NM / self.peak_nm - _VIBRONIC_STEP_EV)
        shoulder_sigma = sigma * _SHOULDER_WIDTH_FACTOR * (shoulder_nm / self.peak_nm) ** 2
        return main + self.shoulder * _split_gaussian(wavelengths, shoulder_nm, shoulder_sigma, shoulder_sigma)


# Starting shapes read off the paper's Fig. 3, and how far the tuning may move them.
_SHAPE_START = {
    "r": PrimaryShape(peak_nm=615.0, fwhm_nm=25.0, skew=0.0, shoulder=0.2),
    "g": PrimaryShape(peak_nm=530.0, fwhm_nm=30.0, skew=0.0, shoulder=0.2),
    "b": PrimaryShape(peak_nm=455.0, fwhm_nm=22.0, skew=0.0, shoulder=0.2),
}
_SHAPE_SCALE = np.array([5.0, 5.0, 0.2, 0.2])  # how far from the start a unit of regularisation allows
_SHAPE_PEAK_TRAVEL_NM = 15.0
_SHAPE_LOWER = np.array([np.nan, 15.0, -0.6, 0.0])  # peak bound is start ± travel
_SHAPE_UPPER = np.array([np.nan, 40.0, 0.6, 0.8])
_XY_WEIGHT = 1e4  # chromaticity residual weight against the shape regularisation
_MAX_UNIT_DRAWS = 50  # draws of a unit's primary before falling back to Table 1's mean


@dataclass(frozen=True)
class HeadsetEffectSpec:
    """One physical effect the simulated headset can show (design §5 vocabulary).

    Attributes
    ----------
    id : str
        The effect id of the diagnostics vocabulary.
    summary : str
        What the effect does to the emitted light.
    magnitude : str
        What the magnitude means, with its unit.
    realistic_range : (float, float)
        Magnitudes seen on real headsets.
    default : float
        Magnitude used when none is given.
    limits : (float, float)
        Magnitudes that make physical sense: ``limits[0] <= m < limits[1]``.
    """

    id: str
    summary: str
    magnitude: str
    realistic_range: tuple
    default: float
    limits: tuple


HEADSET_EFFECTS = {
    spec.id: spec
    for spec in (
        HeadsetEffectSpec(
            "black-offset",
            "the panel and lens emit light at DAC 0 (flare), with Table 1's black chromaticity",
            "black luminance as a fraction of white luminance",
            (0.003, 0.012), 0.004, (0.0, 1.0),
        ),
        HeadsetEffectSpec(
            "channel-interaction",
            "OLED power limiting: loads above one full channel scale the whole output down",
            "fractional luminance loss of full white against R + G + B",
            (0.05, 0.15), 0.10, (0.0, 1.0),
        ),
        HeadsetEffectSpec(
            "chromaticity-shift",
            "each primary's chromaticity moves toward white at low drive, none at full drive",
            "xy distance of a primary from its full-drive chromaticity as the drive tends to 0",
            (0.01, 0.04), 0.02, (0.0, 0.25),
        ),
        HeadsetEffectSpec(
            "tone-curve-shape",
            "black crush: nothing below a DAC threshold, a re-stretched power law above it",
            "fraction of the DAC range crushed to black",
            (0.03, 0.09), 0.05, (0.0, 1.0),
        ),
        HeadsetEffectSpec(
            "temporal-drift",
            f"warm-up: output × (1 − m·exp(−t/τ)), τ = {WARMUP_TAU_FRACTION} × the session length",
            "fractional output deficit at the start of the session",
            (0.03, 0.08), 0.05, (0.0, 1.0),
        ),
        HeadsetEffectSpec(
            "apl-dependence",
            f"automatic brightness limiting: output × 1 up to a frame load of {APL_KNEE_LOAD}, then a "
            f"power law of the load, settling with τ = {APL_TIME_CONSTANT_S} s",
            "fractional luminance loss of a full-field white against a white window below the knee",
            (0.15, 0.45), 0.25, (0.0, 1.0),
        ),
    )
}
"""Registry of the physical effects of :class:`SimulatedHeadset`, by effect id."""


class HeadsetError(ValueError):
    """A headset setting (effect id, magnitude, colorimetry) is unusable; the message says what to give."""


def _split_gaussian(x: np.ndarray, centre: float, sigma_low: float, sigma_high: float) -> np.ndarray:
    sigma = np.where(x < centre, sigma_low, sigma_high)
    return np.exp(-0.5 * ((x - centre) / sigma) ** 2)


@functools.lru_cache(maxsize=1)
def _cmfs() -> np.ndarray:
    """CIE 1931 2° colour matching functions at :data:`WAVELENGTHS_NM`, shape (401, 3)."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy()
    cmfs = cmfs.align(colour.SpectralShape(WAVELENGTHS_NM[0], WAVELENGTHS_NM[-1], 1.0))
    values = np.asarray(cmfs.values, dtype=float)
    values.setflags(write=False)
    return values


def radiance_to_XYZ(spectra) -> np.ndarray:
    """Absolute CIE 1931 XYZ of spectral radiances sampled at :data:`WAVELENGTHS_NM`.

    Parameters
    ----------
    spectra : array_like, shape (..., 401)
        Spectral radiance, W·sr⁻¹·m⁻²·nm⁻¹, 380–780 nm at 1 nm.

    Returns
    -------
    ndarray, shape (..., 3)
        XYZ with Y the luminance in cd/m² (``K_m = 683 lm/W``).
    """
    return float(colour.constants.CONSTANT_K_M) * (np.asarray(spectra, dtype=float) @ _cmfs())


def _xy(spectra: np.ndarray) -> np.ndarray:
    XYZ = radiance_to_XYZ(spectra)
    return XYZ[..., :2] / XYZ.sum(axis=-1, keepdims=True)


def _xyY_to_XYZ(xy, Y: float = 1.0) -> np.ndarray:
    x, y = xy
    return np.array([x / y * Y, Y, (1.0 - x - y) / y * Y])


@functools.lru_cache(maxsize=64)
def _tuned_shape(channel: str, target_xy: tuple) -> PrimaryShape:
    """The primary shape nearest Fig. 3's whose chromaticity is ``target_xy``.

    A small regularised least-squares fit: the xy residual (weighted heavily)
    against the distance of the peak, width, skew and shoulder from the
    starting shape read off Fig. 3.
    """
    start = _SHAPE_START[channel]
    p0 = np.array([start.peak_nm, start.fwhm_nm, start.skew, start.shoulder])
    lower, upper = _SHAPE_LOWER.copy(), _SHAPE_UPPER.copy()
    lower[0], upper[0] = p0[0] - _SHAPE_PEAK_TRAVEL_NM, p0[0] + _SHAPE_PEAK_TRAVEL_NM
    target = np.asarray(target_xy, dtype=float)

    def residuals(p):
        xy = _xy(PrimaryShape(*p).spectrum(WAVELENGTHS_NM))
        return np.r_[(xy - target) * _XY_WEIGHT, (p - p0) / _SHAPE_SCALE]

    fit = least_squares(residuals, p0, bounds=(lower, upper))
    shape = PrimaryShape(*(float(v) for v in fit.x))
    reached = _xy(shape.spectrum(WAVELENGTHS_NM))
    if np.max(np.abs(reached - target)) > 1e-3:
        raise HeadsetError(
            f"no OLED-like {channel} primary reaches chromaticity {tuple(target_xy)} "
            f"(best {tuple(np.round(reached, 4))}); give a chromaticity nearer the spectrum locus"
        )
    return shape


def validate_effects(effects: dict | None) -> dict:
    """Check an effects mapping and return it as ``{id: float magnitude}``.

    Parameters
    ----------
    effects : dict of str to float or None, or None
        Effect id to magnitude; a magnitude of ``None`` takes the effect's
        default.

    Returns
    -------
    dict of str to float

    Raises
    ------
    HeadsetError
        For an unknown id (the message lists the valid ones) or a magnitude
        outside the effect's physical limits.
    """
    checked = {}
    for effect_id, magnitude in (effects or {}).items():
        spec = HEADSET_EFFECTS.get(effect_id)
        if spec is None:
            raise HeadsetError(
                f"unknown headset effect {effect_id!r}; use one of {', '.join(HEADSET_EFFECTS)}"
            )
        value = spec.default if magnitude is None else float(magnitude)
        low, high = spec.limits
        if not (math.isfinite(value) and low <= value < high):
            raise HeadsetError(
                f"effect {effect_id!r}: magnitude {magnitude!r} is outside {low} <= m < {high}; "
                f"give a {spec.magnitude} (realistic {spec.realistic_range[0]}–{spec.realistic_range[1]}, "
                f"default {spec.default})"
            )
        if not spec.realistic_range[0] <= value <= spec.realistic_range[1]:
            _LOG.info("effect %s: magnitude %g is outside the realistic range %s",
                      effect_id, value, spec.realistic_range)
        checked[effect_id] = value
    return checked


def parse_effect(text: str) -> tuple[str, float]:
    """Parse a command-line effect ``ID[:MAGNITUDE]`` into ``(id, magnitude)``.

    Parameters
    ----------
    text : str
        For example ``"channel-interaction:0.1"``, or ``"black-offset"`` for the
        effect's default magnitude.

    Returns
    -------
    (str, float)

    Raises
    ------
    HeadsetError
        For an unknown id, a magnitude that is not a number, or one outside the
        effect's limits; the message says what to write instead.

    Examples
    --------
    >>> parse_effect("channel-interaction:0.1")
    ('channel-interaction', 0.1)
    >>> parse_effect("black-offset")
    ('black-offset', 0.004)
    """
    effect_id, _, magnitude_text = text.strip().partition(":")
    magnitude = None
    if magnitude_text.strip():
        try:
            magnitude = float(magnitude_text)
        except ValueError:
            raise HeadsetError(
                f"effect {text!r}: magnitude {magnitude_text!r} is not a number; "
                "write ID or ID:MAGNITUDE, e.g. channel-interaction:0.1"
            ) from None
    ((effect_id, value),) = validate_effects({effect_id.strip(): magnitude}).items()
    return effect_id, value


class SimulatedHeadset:
    """An OLED HMD emitting spectral radiance, optionally with physical effects.

    Parameters
    ----------
    effects : dict of str to float, optional
        Effect id (a key of :data:`HEADSET_EFFECTS`) to magnitude (``None`` for
        the default). No effects: a clean, additive headset with zero black.
    seed : int, optional
        Draw this unit's chromaticities from the unit-to-unit spread of Table 1
        (its standard deviations); ``None`` gives Table 1's means exactly.
    white_luminance : float
        Luminance (cd/m²) of full white on the clean, additive panel (before
        power limiting and warm-up).
    session_length_s : float
        Expected length of the measurement session; sets the warm-up time
        constant of ``temporal-drift``.
    clock : callable, optional
        Returns the session time in seconds; used by :meth:`current_radiance`.
        By default, seconds since the headset was created.
    characteristics : HeadsetCharacteristics
        The colorimetry to reproduce; Table 1 of the paper by default.

    Examples
    --------
    >>> headset = SimulatedHeadset({"channel-interaction": 0.1})
    >>> headset.radiance([255, 255, 255]).shape
    (401,)
    """

    def __init__(
        self,
        effects: dict | None = None,
        seed: int | None = None,
        white_luminance: float = 100.0,
        *,
        session_length_s: float = 3600.0,
        clock: Callable[[], float] | None = None,
        characteristics: HeadsetCharacteristics = TABLE1_HTC_VIVE,
    ):
        if not (math.isfinite(white_luminance) and white_luminance > 0):
            raise HeadsetError(
                f"white_luminance {white_luminance!r} cd/m² is unusable; give a positive luminance, e.g. 100"
            )
        self.effects = validate_effects(effects)
        self.seed = seed
        self.white_luminance = float(white_luminance)
        self.session_length_s = float(session_length_s)
        self.characteristics = _unit_characteristics(characteristics, seed)
        self.wavelengths = WAVELENGTHS_NM.copy()
        if clock is None:
            start = time.monotonic()
            clock = lambda: time.monotonic() - start  # noqa: E731
        self._clock = clock
        self._shown = np.zeros(_N_CHANNELS)
        self._shown_window = 1.0
        self._shown_surround = np.zeros(_N_CHANNELS)
        self._build_spectra()
        self._apl_from = 1.0  # limiter gain when the frame last changed
        self._apl_changed_at = -math.inf

    # -- construction -------------------------------------------------------------------

    def _build_spectra(self) -> None:
        ch = self.characteristics
        shapes = [_tuned_shape(c, tuple(ch.primaries_xy[c])) for c in _CHANNELS]
        self.primary_shapes = dict(zip(_CHANNELS, shapes))
        unit = np.array([s.spectrum(WAVELENGTHS_NM) for s in shapes])
        unit /= radiance_to_XYZ(unit)[:, 1:2]  # each row: 1 cd/m²
        primaries_XYZ = radiance_to_XYZ(unit).T  # columns: XYZ of each primary at 1 cd/m²
        white_XYZ = _xyY_to_XYZ(ch.white_xy, self.white_luminance)
        self.channel_luminances = np.linalg.solve(primaries_XYZ, white_XYZ)
        if np.any(self.channel_luminances <= 0):
            raise HeadsetError(
                f"white {ch.white_xy} lies outside the triangle of the primaries "
                f"{ch.primaries_xy}; give a white inside it"
            )
        self._unit_primaries = unit
        white = self.channel_luminances @ unit
        self._unit_white = white / self.white_luminance
        self._gammas = np.array([ch.gammas[c] for c in _CHANNELS])
        # black/flare: a mixture of the primaries with Table 1's black chromaticity
        black_weights = np.linalg.solve(primaries_XYZ, _xyY_to_XYZ(ch.black_xy))
        if np.any(black_weights < 0):
            raise HeadsetError(
                f"black chromaticity {ch.black_xy} lies outside the triangle of the primaries; give one inside it"
            )
        self._unit_black = black_weights @ unit
        self._shift_beta0 = self._solve_shift_beta0(self.effects.get("chromaticity-shift", 0.0))
        current = self.channel_luminances / np.array([OLED_CURRENT_EFFICIENCY_CD_PER_A[c] for c in _CHANNELS])
        self.apl_power_shares = current / current.sum()
        loss = self.effects.get("apl-dependence", 0.0)
        self._apl_exponent = math.log(1.0 - loss) / math.log(APL_KNEE_LOAD) if loss > 0 else 0.0

    def _solve_shift_beta0(self, distance: float) -> np.ndarray:
        """Per-channel white fraction at drive 0 that moves xy by ``distance``."""
        beta0 = np.zeros(_N_CHANNELS)
        if distance == 0:
            return beta0
        for i, c in enumerate(_CHANNELS):
            primary_xy = _xy(self._unit_primaries[i])

            def moved(beta, i=i, primary_xy=primary_xy):
                mixed = (1 - beta) * self._unit_primaries[i] + beta * self._unit_white
                return float(np.hypot(*(_xy(mixed) - primary_xy))) - distance

            if moved(1.0) <= 0:
                raise HeadsetError(
                    f"effect 'chromaticity-shift': magnitude {distance} is at least the distance from the "
                    f"{c} primary to white; give a smaller shift (realistic "
                    f"{HEADSET_EFFECTS['chromaticity-shift'].realistic_range})"
                )
            beta0[i] = brentq(moved, 0.0, 1.0, xtol=1e-12)
        return beta0

    # -- the light ----------------------------------------------------------------------

    def radiance(self, rgb_dac, t_s: float = 0.0, *, window=1.0, surround=None,
                 apl_gain=None) -> np.ndarray:
        """Spectral radiance emitted for DAC values ``rgb_dac`` at session time ``t_s``.

        Parameters
        ----------
        rgb_dac : array_like, shape (3,) or (N, 3)
            DAC values, 0..255 (floats allowed).
        t_s : float
            Session time in seconds (only ``temporal-drift`` depends on it).
        window : float or array_like, shape (N,)
            The patch's fraction of the field, 0 < window <= 1 (1: full field).
        surround : array_like, shape (3,) or (N, 3), optional
            DAC values of the rest of the field; black by default.
        apl_gain : float, optional
            The ``apl-dependence`` limiter's gain; by default its settled
            value for this frame (see :meth:`apl_gain`).

        Returns
        -------
        ndarray, shape (401,) or (N, 401)
            Spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹ at :attr:`wavelengths`.
        """
        rgb = np.asarray(rgb_dac, dtype=float)
        if rgb.shape[-1:] != (_N_CHANNELS,) or rgb.ndim > 2:
            raise ValueError(f"rgb_dac has shape {rgb.shape}; give 3 DAC values or an (N, 3) array")
        if not np.all(np.isfinite(rgb)) or np.any((rgb < 0) | (rgb > 255)):
            raise ValueError(f"rgb_dac {rgb.tolist()} is outside 0..255; give 8-bit DAC values")
        if not math.isfinite(t_s):
            raise ValueError(f"t_s {t_s!r} is not finite; give the session time in seconds")
        drive = np.atleast_2d(rgb) / 255.0
        linear = self._tone_curve(drive)
        if apl_gain is None:
            apl_gain = self.apl_gain(self.frame_load(rgb, window, surround))
        luminance = linear * self.channel_luminances  # (N, 3) cd/m² per channel
        beta = self._shift_beta0 * (1.0 - drive) ** 2
        spectra = (luminance * (1.0 - beta)) @ self._unit_primaries
        spectra += (luminance * beta).sum(axis=1, keepdims=True) * self._unit_white
        spectra *= (self._power_limit(linear) * np.reshape(apl_gain, -1))[:, None]
        spectra += self.effects.get("black-offset", 0.0) * self.white_luminance * self._unit_black
        spectra *= self._warmup(t_s)
        return spectra[0] if rgb.ndim == 1 else spectra

    def _tone_curve(self, drive: np.ndarray) -> np.ndarray:
        crushed = self.effects.get("tone-curve-shape", 0.0)
        stretched = np.clip((drive - crushed) / (1.0 - crushed), 0.0, 1.0)
        return stretched ** self._gammas

    def _power_limit(self, linear: np.ndarray) -> np.ndarray:
        loss = self.effects.get("channel-interaction", 0.0)
        single_channel_load = 1.0 / _N_CHANNELS
        excess = np.clip((linear.mean(axis=1) - single_channel_load) / (1.0 - single_channel_load), 0.0, 1.0)
        return 1.0 - loss * excess

    def frame_load(self, rgb_dac, window=1.0, surround=None) -> np.ndarray:
        """Load of frames showing ``rgb_dac`` as a ``window`` on ``surround`` (full-field white = 1).

        Returns
        -------
        ndarray, shape (N,)
            ``Σ_c p_c (w·lin_c(patch) + (1 − w)·lin_c(surround))``, ``p_c`` =
            :attr:`apl_power_shares`.
        """
        rgb = np.atleast_2d(np.asarray(rgb_dac, dtype=float))
        window = np.broadcast_to(np.asarray(window, dtype=float), (len(rgb),))
        if not np.all((window > 0) & (window <= 1)):
            raise ValueError(f"window {window.tolist()} is outside (0, 1]; give the patch's fraction of the field")
        surround = np.zeros_like(rgb) if surround is None else np.atleast_2d(np.asarray(surround, dtype=float))
        if surround.shape[-1] != _N_CHANNELS or np.any((surround < 0) | (surround > 255)) \
                or not np.all(np.isfinite(surround)):
            raise ValueError(f"surround {surround.tolist()} is not DAC values 0..255; give 3 per patch")
        w = window[:, None]
        linear = w * self._tone_curve(rgb / 255.0) + (1.0 - w) * self._tone_curve(surround / 255.0)
        return linear @ self.apl_power_shares

    def apl_gain(self, load) -> np.ndarray:
        """Settled gain of the ``apl-dependence`` limiter at frame ``load`` (1 without the effect)."""
        load = np.asarray(load, dtype=float)
        return np.where(load > APL_KNEE_LOAD,
                        (APL_KNEE_LOAD / np.maximum(load, APL_KNEE_LOAD)) ** self._apl_exponent, 1.0)

    def _apl_gain_now(self, t_s: float) -> float:
        target = float(self.apl_gain(self.frame_load(self._shown, self._shown_window, self._shown_surround))[0])
        elapsed = max(t_s - self._apl_changed_at, APL_READ_DELAY_S)
        return target + (self._apl_from - target) * math.exp(-elapsed / APL_TIME_CONSTANT_S)

    def _warmup(self, t_s: float) -> float:
        deficit = self.effects.get("temporal-drift", 0.0)
        return 1.0 - deficit * math.exp(-max(t_s, 0.0) / self.warmup_tau_s)

    @property
    def session_length_s(self) -> float:
        """Expected length (s) of the session the headset is measured in."""
        return self._session_length_s

    @session_length_s.setter
    def session_length_s(self, seconds: float) -> None:
        if not (math.isfinite(seconds) and seconds > 0):
            raise HeadsetError(
                f"session_length_s {seconds!r} is unusable; give the expected session length in seconds"
            )
        self._session_length_s = float(seconds)

    @property
    def warmup_tau_s(self) -> float:
        """Time constant (s) of the ``temporal-drift`` warm-up."""
        return WARMUP_TAU_FRACTION * self.session_length_s

    # -- what is on screen --------------------------------------------------------------

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        """Put a patch of DAC values ``rgb_dac`` (3,) on the screen.

        Parameters
        ----------
        rgb_dac : array_like, shape (3,)
        window : float
            The patch's fraction of the field (1: full field).
        surround : array_like, shape (3,)
            DAC values of the rest of the field.
        """
        rgb = np.asarray(rgb_dac, dtype=float)
        if rgb.shape != (_N_CHANNELS,):
            raise ValueError(f"show() takes one patch of 3 DAC values, got shape {rgb.shape}")
        surround = np.asarray(surround, dtype=float)
        if surround.shape != (_N_CHANNELS,):
            raise ValueError(f"show() takes a surround of 3 DAC values, got shape {surround.shape}")
        self.radiance(rgb, window=window, surround=surround)  # validates the values
        now = self._clock()
        self._apl_from = self._apl_gain_now(now)
        self._apl_changed_at = now
        self._shown = rgb.copy()
        self._shown_window = float(window)
        self._shown_surround = surround.copy()

    @property
    def shown(self) -> np.ndarray:
        """DAC values of the patch on screen now (black until :meth:`show` is called)."""
        return self._shown.copy()

    @property
    def shown_window(self) -> float:
        """Fraction of the field the patch on screen covers."""
        return self._shown_window

    @property
    def shown_surround(self) -> np.ndarray:
        """DAC values of the surround on screen now."""
        return self._shown_surround.copy()

    def current_radiance(self) -> np.ndarray:
        """Spectral radiance (401,) of the patch on screen, at the session clock's time."""
        t_s = self._clock()
        return self.radiance(self._shown, t_s, window=self._shown_window, surround=self._shown_surround,
                             apl_gain=self._apl_gain_now(t_s))

    def describe(self) -> str:
        """One line naming the headset and its effects, for journals and logs."""
        effects = ", ".join(f"{k}={v:g}" for k, v in self.effects.items()) or "no effects"
        unit = "Table 1 means" if self.seed is None else f"unit seed {self.seed}"
        return f"simulated OLED HMD ({unit}, white {self.white_luminance:g} cd/m², {effects})"


def _unit_characteristics(nominal: HeadsetCharacteristics, seed: int | None) -> HeadsetCharacteristics:
    """One unit drawn from the spread of ``nominal`` (or ``nominal`` itself without a seed).

    Each chromaticity is drawn from a normal distribution with Table 1's mean
    and standard deviation; a primary drawn outside what an OLED emitter can
    reach (beyond the spectrum locus) is drawn again.
    """
    if seed is None:
        return nominal
    rng = np.random.default_rng(seed)

    def draw(mean, sd):
        return tuple(round(float(v), 4) for v in rng.normal(mean, sd))

    def reachable(channel, xy) -> bool:
        try:
            _tuned_shape(channel, xy)
        except HeadsetError:
            return False
        return True

    primaries = {}
    for c in _CHANNELS:
        for _ in range(_MAX_UNIT_DRAWS):
            xy = draw(nominal.primaries_xy[c], nominal.primaries_xy_sd[c])
            if reachable(c, xy):
                break
        else:
            xy = tuple(nominal.primaries_xy[c])
        primaries[c] = xy
    return HeadsetCharacteristics(
        primaries_xy=primaries,
        white_xy=draw(nominal.white_xy, nominal.white_xy_sd),
        black_xy=draw(nominal.black_xy, nominal.black_xy_sd),
        gammas=dict(nominal.gammas),
        primaries_xy_sd=nominal.primaries_xy_sd,
        white_xy_sd=nominal.white_xy_sd,
        black_xy_sd=nominal.black_xy_sd,
    )
