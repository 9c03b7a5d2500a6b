"""An independent simulated display: effects in forms the extension does not share, noise of its own.

The simulated headset (``instruments/headset.py``) and the extended model
(``workbench/display/extended.py``) were written together: hiding the
headset's effects and finding them with the extension's forms proves little.
This generator shares none of their functional forms. It draws a display
(primaries, white, per-channel power laws: the paper's model, exactly, when
no effect is on), measures the ``paper`` plan on it with a noise model of its
own, and hides effects in these forms:

``black-offset``
    ``bluish`` or ``reddish``: a constant black of its own chromaticity
    (far from the white's), 0.15–1 % of white.
``channel-interaction``
    ``backlight``: a dynamic-contrast backlight whose gain follows the
    *drive* (not the light) of the channels beyond the brightest,
    ``1 + k·(Σd − max d)/2``, k = ±(5–15) %;
    ``crosstalk``: each channel's light is scaled by the drive of the other
    two with a per-channel coupling (a chromatic non-additivity);
    ``power-limit``: the output falls once the luminance-weighted load
    passes a knee above any single channel's share, 5–15 % at white.
    Single-channel sweeps are untouched by all three.
    ``power-limit-quadratic``: the panel dims the whole frame as its load
    grows, gain ``1 − k·load²`` (load: the luminance-weighted mean channel
    light, 1 at white), k = 5–15 %: the sweeps dim too;
    ``knee``: no loss below a load of 0.4–0.6, then a linear loss reaching
    5–15 % at white (the brighter sweeps pass the knee);
    ``drive-crosstalk``: each lit channel's *drive* picks up a share s = 2–6 %
    of its two neighbours' drives before the power law,
    ``d_c' = min(1, d_c + s·(d_a + d_b)/2)`` where ``d_c > 0`` (a channel at
    drive 0 is off and stays dark): a sweep's lit channel has dark
    neighbours and its dark channels stay dark (untouched), white stays
    additive (clipped at full drive), greys and mixtures brighten.
``chromaticity-shift``
    ``leak``: a fraction ``β₀(1 − d)^1.5`` of each channel's light has a
    fixed leak chromaticity; ``log-desaturation``: the fraction grows with
    ``−ln d`` toward the white's chromaticity; xy distance 0.01–0.04 at the
    lowest drive.
``tone-curve-shape``
    ``shoulder`` (compression toward full drive), ``s-curve`` (a blend with
    a smoothstep of the power law), ``soft-toe`` (a softplus black crush);
    1.5–6 % of full output from the nearest power law.
    ``shoulder-soft``: ``(1 − e^(−a·L))/(1 − e^(−a))`` of the power-law light
    ``L`` (a soft saturation toward full drive); ``toe``: a shadow lift
    with a drive threshold, ``max(0, L + c·(B(d)(1 − d) − (1 − d)^8))`` with
    the bump ``B(d) = (d/0.15)·e^(1 − d/0.15)``: nothing below about DAC 13,
    the shadows above it lifted. For these two the magnitude is drawn as the
    distance itself (1.5–6 % of full output, the largest of the three
    channels, sup over the 256 DAC codes, from the nearest power law) and
    the parameter solved for it.
``temporal-drift``
    ``warm-up`` (``1 − m/(1 + (t/τ)²)``), ``decline`` (linear), ``step``
    (at 30–70 % of the session), ``wander`` (two incommensurate sines);
    2–8 % peak to peak.

The forms the seeded acceptance suite hides are :data:`SUITE_FORMS` (the
forms above the later additions, whose sessions, draws and seeds are kept
bit for bit); :data:`NEW_FORMS` are the additions and :data:`PAIRED_FORMS`
names pairs a reviewer asked for. Every form draws its magnitudes from the
session's stream only when it is hidden, so adding forms changes no earlier
session.

The result keeps the display, so the truth is known for any colour
(:meth:`GeneratedSession.true_at`, :meth:`GeneratedSession.reference_XYZ`:
the display in the state of the last two white references, the state a
drift-corrected profile describes) and a bench can score a profile on
colours no plan measured (:func:`hidden_colours`). Plans: any built-in plan
name (``paper``, ``paper+greys``, ``authors-2024``, …).

Noise: per measurement a Student-t (6 dof) whole-measurement gain scaled to
``a`` (0.05–0.5 %), per-coordinate noise 0.3·a, a shot-noise term ``∝ √Y``
and a constant floor. Imports nothing from ``instruments`` nor the
extension; the plan's patch list is the only thing it takes from the
workbench (and :class:`~workbench.session.Session` to hold the result).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from workbench.measurement.plans import measurement_plan
from workbench.session import Session

__all__ = ["FORMS", "SUITE_FORMS", "NEW_FORMS", "PAIRED_FORMS", "PROBES", "GeneratedSession",
           "generate_session", "hidden_colours", "nearest_power_law_distance"]

SUITE_FORMS = {
    "black-offset": ("bluish", "reddish"),
    "channel-interaction": ("backlight", "crosstalk", "power-limit"),
    "chromaticity-shift": ("leak", "log-desaturation"),
    "tone-curve-shape": ("shoulder", "s-curve", "soft-toe"),
    "temporal-drift": ("warm-up", "decline", "step", "wander"),
}
"""Effect id → the forms the seeded acceptance suite hides (fixed: its sessions and seeds)."""

NEW_FORMS = {
    "channel-interaction": ("power-limit-quadratic", "knee", "drive-crosstalk"),
    "tone-curve-shape": ("shoulder-soft", "toe"),
}
"""Effect id → the forms added after the suite was fixed (a reviewer's list)."""

FORMS = {effect: forms + NEW_FORMS.get(effect, ()) for effect, forms in SUITE_FORMS.items()}
"""Effect id → every form this generator hides it in."""

PAIRED_FORMS = {
    "warm-up beside sweeps": {"temporal-drift": "warm-up"},
    "bluish + log-desaturation": {"black-offset": "bluish", "chromaticity-shift": "log-desaturation"},
    "bluish + step": {"black-offset": "bluish", "temporal-drift": "step"},
}
"""Named scenarios a reviewer asked for: a warm-up while the sweeps are measured (on every
plan, the authors' too), a bluish black beside a chromaticity shift toward the white, and a
bluish black beside a step drift."""


PROBES = {
    "wide-gamut": "primaries near ITU-R BT.2020's (a wide-gamut OLED or laser panel), gammas "
                  "1.8–2.8, white 20–400 cd/m²",
    "chromaticity-noise": "the noise a spectroradiometer's datasheet states instead of the "
                          "generator's: chromaticity repeatability ±0.0002 in x and y (growing "
                          "as 1/√Y below 1 % of white), luminance noise a, and the floor on X, "
                          "Y and Z",
    "correlated-noise": "the generator's noise plus a slow gain as large as its gain noise that "
                        "carries over from reading to reading (AR(1), φ 0.9): a lamp or panel "
                        "that flickers over a few patches",
    "current-load": "a power limit (power-limit, power-limit-quadratic, knee) that loads the "
                    "panel by the current each channel draws, not by its light: an OLED's blue "
                    "subpixels give 5–12 cd/A, green 50–100, red 20–40, so blue weighs several "
                    "times its share of the white's luminance",
}
"""Probe id → what it changes: a display or a noise none of the generator's forms draws, to see a
diagnosis hold on what it was not tuned on (``generate_session(probe=…)``). Each draws from a
stream of its own (:data:`PROBE_STREAM`), so a session without a probe is bit for bit as before,
and a probe's session keeps the display, the effects and the noise draws of the same seed, less
what the probe replaces."""

PROBE_STREAM = 0x9B0BE
"""Tag of a probe's stream: ``[session seed, PROBE_STREAM, part]``."""

BT2020_PRIMARIES_XY = np.array([[0.708, 0.292], [0.170, 0.797], [0.131, 0.046]])
"""ITU-R BT.2020's primaries (CIE 1931 xy), the ``wide-gamut`` probe's centre."""


@dataclass(frozen=True)
class GeneratedSession:
    session: Session
    effects: dict = field(default_factory=dict)  # effect → (form, magnitude)
    noise: float = 0.0
    true_XYZ: np.ndarray | None = None  # noiseless, effects on, at each row's time
    effect_free_XYZ: np.ndarray | None = None  # noiseless, no effect
    display: "_Display | None" = None  # the display itself, effects on
    effect_free_display: "_Display | None" = None  # the same draws, no effect
    plan: str = "paper"
    probe: str | None = None  # a key of PROBES, or None

    def true_at(self, rgb, t=None) -> np.ndarray:
        """Noiseless XYZ of DAC triplets ``rgb`` (N, 3) at time(s) ``t`` (s; the session's end
        when None), effects on."""
        rgb = np.atleast_2d(np.asarray(rgb, dtype=float))
        t = np.full(len(rgb), self.display.session_s) if t is None else np.broadcast_to(
            np.asarray(t, dtype=float), (len(rgb),))
        return self.display.XYZ(rgb, t)

    def effect_free_at(self, rgb, t=None) -> np.ndarray:
        """The same display with no effect (the paper's model exactly); ``t`` is ignored."""
        rgb = np.atleast_2d(np.asarray(rgb, dtype=float))
        return self.effect_free_display.XYZ(rgb, np.zeros(len(rgb)))

    @property
    def reference_gain(self) -> float:
        """The drift's gain in the reference state: the mean over the last two white rows (1
        without drift), as a drift correction normalizes."""
        if self.display.drift is None:
            return 1.0
        session = self.session
        whites = np.flatnonzero(session.mask("white"))[-2:]
        return float(np.mean(self.display._drift(session.t_s[whites])))

    def reference_XYZ(self, rgb) -> np.ndarray:
        """Noiseless XYZ of ``rgb`` in the reference state (:attr:`reference_gain`): the
        display a profile of this session should predict."""
        rgb = np.atleast_2d(np.asarray(rgb, dtype=float))
        return self.display.light(rgb) * self.reference_gain


def hidden_colours(n: int = 300, seed: int = 0) -> np.ndarray:
    """``n`` seeded random DAC triplets (uniform over the 8-bit cube), a stream no plan uses."""
    return np.random.default_rng([int(seed), 0x41DDE1]).integers(0, 256, size=(n, 3)).astype(float)


_CODES = np.arange(256) / 255.0
_GAMMA_GRID = np.arange(0.3, 6.0, 0.02)


def nearest_power_law_distance(output, drive=_CODES) -> float:
    """``min over γ of max |output − drive^γ|``: a tone curve's distance from every power law."""
    output = np.asarray(output, dtype=float)
    distance = np.max(np.abs(output[None, :] - drive[None, :] ** _GAMMA_GRID[:, None]), axis=1)
    best = _GAMMA_GRID[np.argmin(distance)]
    fine = np.linspace(best - 0.02, best + 0.02, 41)
    return float(np.min(np.max(np.abs(output[None, :] - drive[None, :] ** fine[:, None]), axis=1)))


def _unit(xy) -> np.ndarray:
    x, y = xy
    return np.array([x / y, 1.0, (1 - x - y) / y])


def _xy(XYZ):
    XYZ = np.asarray(XYZ, dtype=float)
    return XYZ[..., :2] / XYZ.sum(axis=-1, keepdims=True)


TOE_BUMP = 0.15
"""Drive where the ``toe`` form's shadow lift peaks (before the threshold's pull)."""


class _Display:
    def __init__(self, rng: np.random.Generator):
        self.primaries_xy = np.array([
            [0.64 + rng.uniform(-0.02, 0.03), 0.33 + rng.uniform(-0.01, 0.01)],
            [0.30 + rng.uniform(-0.06, 0.02), 0.60 + rng.uniform(-0.02, 0.08)],
            [0.15 + rng.uniform(-0.01, 0.01), 0.06 + rng.uniform(-0.015, 0.02)]])
        self.white_xy = np.array([0.3127, 0.3290]) + rng.uniform(-0.01, 0.01, 2)
        self.white_Y = rng.uniform(60.0, 250.0)
        units = np.column_stack([_unit(p) for p in self.primaries_xy])
        shares = np.linalg.solve(units, _unit(self.white_xy))
        self.columns = units * shares * self.white_Y  # XYZ of each full primary
        self.shares = shares  # luminance share of each channel in white
        self.load_weights = None  # what a power limit's load weighs each channel by (None: shares)
        self.gammas = rng.uniform(1.9, 2.6, 3)
        self.tone = None  # (form, parameter)
        self.black = np.zeros(3)
        self.interaction = None
        self.chromaticity = None
        self.drift = None
        self.session_s = 1.0

    # -- the light ---------------------------------------------------------------------
    def linear(self, d):
        L = d ** self.gammas
        if self.tone is None:
            return L
        form, p = self.tone
        if form == "shoulder-soft":
            return np.expm1(-p * L) / np.expm1(-p)
        if form == "toe":
            bump = (d / TOE_BUMP) * np.exp(1 - d / TOE_BUMP)
            return np.maximum(0.0, L + p * (bump * (1 - d) - (1 - d) ** 8))
        if form == "shoulder":
            return (1 + p) * L / (1 + p * L ** 3)
        if form == "s-curve":
            return (1 - p) * L + p * (3 * L ** 2 - 2 * L ** 3)
        # soft-toe: a softplus black crush at d0 = p, width p/4
        width = p / 4
        def crush(x):
            return width * np.logaddexp(0.0, (x - p) / width)
        return (crush(d) / crush(1.0)) ** self.gammas

    def XYZ(self, rgb, t):
        light = self.light(rgb)
        if self.drift is not None:
            light *= self._drift(t)[:, None]
        return light

    def _drive(self, d):
        """drive-crosstalk: each lit channel's drive picks up a share of its neighbours' (clipped
        at 1); a channel at drive 0 is off and picks up nothing."""
        if self.interaction is None or self.interaction[0] != "drive-crosstalk":
            return d
        share = self.interaction[1]
        picked = share * (d.sum(axis=1, keepdims=True) - d) / 2
        return np.where(d > 0, np.minimum(1.0, d + picked), d)

    def light(self, rgb):
        """Noiseless XYZ of ``rgb`` (N, 3) without the drift."""
        d = self._drive(np.clip(rgb / 255.0, 0, 1))
        L = self.linear(d)
        light = np.zeros((len(d), 3))
        for c in range(3):
            unit = np.tile(self.columns[:, c] / self.columns[1, c], (len(d), 1))
            if self.chromaticity is not None:
                form, beta0, target = self.chromaticity
                if form == "leak":
                    beta = beta0 * (1 - d[:, c]) ** 1.5
                else:
                    beta = beta0 * np.clip(-np.log(np.maximum(d[:, c], 1e-3)) / np.log(50), 0, 1)
                unit = (1 - beta)[:, None] * unit + beta[:, None] * _unit(target)
            light += (self.columns[1, c] * L[:, c])[:, None] * unit * self._coupling(d, L, c)[:, None]
        light *= self._gain(d, L)[:, None]
        light += self.black
        return light

    def _coupling(self, d, L, c):
        if self.interaction is None or self.interaction[0] != "crosstalk":
            return np.ones(len(d))
        _, k, coupling = self.interaction
        others = d.sum(axis=1) - d[:, c]
        return 1 + k * coupling[c] * others / 2

    def _gain(self, d, L):
        if self.interaction is None:
            return np.ones(len(d))
        form, k, _ = self.interaction
        weights = self.shares if self.load_weights is None else self.load_weights
        if form == "backlight":
            return 1 + k * (d.sum(axis=1) - d.max(axis=1)) / 2
        if form == "power-limit":
            load = L @ weights
            knee = weights.max() + 0.03
            return 1 - k * np.clip((load - knee) / (1 - knee), 0, 1)
        if form == "power-limit-quadratic":
            return 1 - k * (L @ weights) ** 2
        if form == "knee":
            knee = self.interaction[2]
            return 1 - k * np.clip((L @ weights - knee) / (1 - knee), 0, 1)
        return np.ones(len(d))

    def _drift(self, t):
        form, m, p = self.drift
        T = self.session_s
        if form == "warm-up":
            return 1 - m / (1 + (t / (p * T)) ** 2)
        if form == "decline":
            return 1 - m * t / T
        if form == "step":
            return np.where(t < p * T, 1.0, 1.0 - m)
        phase1, phase2 = p
        return 1 + m / 2 * (0.6 * np.sin(2 * np.pi * 1.7 * t / T + phase1)
                            + 0.4 * np.sin(2 * np.pi * 2.9 * t / T + phase2))


def _hide(display: _Display, effect: str, form: str, rng: np.random.Generator) -> float:
    """Switch ``effect`` on in ``form`` with a random magnitude; return the magnitude."""
    if effect == "black-offset":
        level = rng.uniform(0.0015, 0.01)
        xy = (0.24, 0.22) if form == "bluish" else (0.37, 0.31)
        display.black = _unit(xy) * level * display.white_Y
        return level
    if form in NEW_FORMS.get(effect, ()):
        return _hide_new(display, effect, form, rng)
    if effect == "channel-interaction":
        k = rng.uniform(0.05, 0.15)
        if form == "backlight":
            k *= rng.choice([-1.0, 1.0])
        coupling = np.array([1.0, 0.5, -0.4])[rng.permutation(3)]
        display.interaction = (form, k, coupling)
        return k
    if effect == "chromaticity-shift":
        distance = rng.uniform(0.01, 0.04)
        target = (0.33, 0.36) if form == "leak" else tuple(display.white_xy)
        display.chromaticity = (form, 0.0, target)
        # β₀ so that the xy distance of the farthest-moving primary at DAC 13 is ``distance``
        low = np.array([[13.0, 0, 0], [0, 13.0, 0], [0, 0, 13.0]])
        reference = _xy(display.columns.T)
        low_beta, high_beta = 0.0, 1.0
        for _ in range(40):
            beta0 = (low_beta + high_beta) / 2
            display.chromaticity = (form, beta0, target)
            moved = _xy(display.XYZ(low, np.zeros(3)) - display.black)
            if np.max(np.linalg.norm(moved - reference, axis=1)) > distance:
                high_beta = beta0
            else:
                low_beta = beta0
        return distance
    if effect == "tone-curve-shape":
        parameter = {"shoulder": rng.uniform(0.15, 0.5), "s-curve": rng.uniform(0.12, 0.35),
                     "soft-toe": rng.uniform(0.03, 0.08)}[form]
        display.tone = (form, parameter)
        return parameter
    if effect == "temporal-drift":
        m = rng.uniform(0.02, 0.08)
        parameter = {"warm-up": rng.uniform(0.08, 0.25), "decline": None,
                     "step": rng.uniform(0.3, 0.7),
                     "wander": tuple(rng.uniform(0, 2 * np.pi, 2))}[form]
        display.drift = (form, m, parameter)
        return m
    raise ValueError(f"unknown effect {effect!r}; use one of {sorted(FORMS)}")


def _tone_distance(display: _Display) -> float:
    """The largest channel's distance of the display's tone curves from the nearest power law."""
    output = display.linear(np.repeat(_CODES[:, None], 3, axis=1))
    return max(nearest_power_law_distance(output[:, c]) for c in range(3))


def _hide_new(display: _Display, effect: str, form: str, rng: np.random.Generator) -> float:
    """:data:`NEW_FORMS`: their draws come after the display's, only when they are hidden."""
    if effect == "channel-interaction":
        if form == "drive-crosstalk":
            share = rng.uniform(0.02, 0.06)
            display.interaction = (form, share, None)
            return share
        k = rng.uniform(0.05, 0.15)  # the loss at white (load 1)
        display.interaction = (form, k, rng.uniform(0.4, 0.6) if form == "knee" else None)
        return k
    # tone-curve-shape: the distance from the nearest power law is drawn, the parameter solved
    distance = rng.uniform(0.015, 0.06)
    low, high = 0.0, {"shoulder-soft": 20.0, "toe": 0.5}[form]
    for _ in range(30):
        parameter = (low + high) / 2
        display.tone = (form, parameter)
        if _tone_distance(display) > distance:
            high = parameter
        else:
            low = parameter
    display.tone = (form, (low + high) / 2)
    return float(_tone_distance(display))


def _widen(display: "_Display", rng: np.random.Generator) -> None:
    """The ``wide-gamut`` probe: primaries within ±0.01 of BT.2020's (blue within ±0.003 in x,
    ±0.002 in y), white 20–400 cd/m², gammas 1.8–2.8; the white's chromaticity kept."""
    spread = np.array([[0.01, 0.01], [0.01, 0.01], [0.003, 0.002]])
    display.primaries_xy = BT2020_PRIMARIES_XY + rng.uniform(-1.0, 1.0, (3, 2)) * spread
    display.white_Y = rng.uniform(20.0, 400.0)
    units = np.column_stack([_unit(p) for p in display.primaries_xy])
    display.shares = np.linalg.solve(units, _unit(display.white_xy))
    display.columns = units * display.shares * display.white_Y
    display.gammas = rng.uniform(1.8, 2.8, 3)


def _current_load(display: "_Display", rng: np.random.Generator) -> None:
    """The ``current-load`` probe: a power limit's load weighs each channel by the current it
    draws at full drive, its luminance share over its efficiency (cd/A: red 20–40, green 50–100,
    blue 5–12, an OLED's spread), normalized to 1 at white."""
    efficiency = rng.uniform([20.0, 50.0, 5.0], [40.0, 100.0, 12.0])
    current = display.shares / efficiency
    display.load_weights = current / current.sum()


def _chromaticity_noise(XYZ: np.ndarray, display: "_Display", a: float, floor: float,
                        rng: np.random.Generator) -> np.ndarray:
    """The ``chromaticity-noise`` probe: ``XYZ`` read with x and y each off by ±0.0002 (times
    √(1 % of white / Y) below 1 % of white) and Y by ``a`` of itself, then the ``floor`` on each
    of X, Y and Z (a dark signal is the sensor's, not the stimulus's: it does not scale with a
    deep blue's Z/Y)."""
    Y = XYZ[:, 1]
    total = XYZ.sum(axis=1)
    lit = total > 1e-9 * display.white_Y
    xy = np.where(lit[:, None], XYZ[:, :2] / np.where(lit, total, 1.0)[:, None],
                  display.white_xy[None, :])
    dim = np.sqrt(0.01 * display.white_Y / np.maximum(Y, 1e-6 * display.white_Y))
    xy = xy + 0.0002 * np.maximum(1.0, dim)[:, None] * rng.standard_normal((len(Y), 2))
    Y = Y * (1.0 + a * rng.standard_normal(len(Y)))
    x, y = xy[:, 0], xy[:, 1]
    return (np.column_stack([x / y * Y, Y, (1.0 - x - y) / y * Y])
            + floor * rng.standard_normal((len(Y), 3)))


def _slow_gain(n: int, a: float, rng: np.random.Generator, carry: float = 0.9) -> np.ndarray:
    """The ``correlated-noise`` probe's gain: an AR(1) series of standard deviation ``a``."""
    step = rng.standard_normal(n)
    series = np.empty(n)
    series[0] = step[0]
    for k in range(1, n):
        series[k] = carry * series[k - 1] + np.sqrt(1.0 - carry ** 2) * step[k]
    return a * series


def generate_session(effects: dict | None = None, seed: int = 0,
                     noise: float | None = None, plan: str = "paper",
                     probe: str | None = None) -> GeneratedSession:
    """A plan (``paper`` unless told) measured on an independent display with ``effects`` hidden.

    Parameters
    ----------
    effects : dict or str
        Effect id → form (a value of :data:`FORMS`), or a name of :data:`PAIRED_FORMS`.
    seed : int
        Seeds the display, the magnitudes, the plan's validation colours and the noise.
    noise : float, optional
        Relative gain noise ``a``; drawn from 0.05–0.5 % when None.
    plan : str
        The built-in measurement plan measured (``paper+greys`` adds greys and
        partial-drive mixtures to the fit rows; ``authors-2024`` is the seed
        authors' own plan, with a grey ramp). The display and its effects are
        drawn before the plan is read: one seed is one display on every plan.
    probe : str, optional
        A key of :data:`PROBES`: a display or a noise the generator's forms do not draw.

    The result also holds the noiseless truth (``true_XYZ``: the display with
    its effects, at each row's time) and ``effect_free_XYZ`` (the same display
    with no effect: the paper's model exactly), so a suite can tell how much
    each session's effects change the colours it holds out.
    """
    plan_name = plan
    if isinstance(effects, str):
        effects = PAIRED_FORMS[effects]
    if probe is not None and probe not in PROBES:
        raise ValueError(f"no probe {probe!r}; use one of {sorted(PROBES)}")
    rng = np.random.default_rng([seed, 90411])
    display = _Display(rng)
    if probe == "wide-gamut":
        _widen(display, np.random.default_rng([seed, PROBE_STREAM, 0]))
    elif probe == "current-load":
        _current_load(display, np.random.default_rng([seed, PROBE_STREAM, 3]))
    hidden = {}
    for effect, form in (effects or {}).items():
        if form not in FORMS[effect]:
            raise ValueError(f"{effect} has no form {form!r}; use one of {FORMS[effect]}")
        hidden[effect] = (form, _hide(display, effect, form, rng))
    a = float(rng.uniform(0.0005, 0.005)) if noise is None else float(noise)
    plan = measurement_plan(plan, seed)
    rgb = np.array([patch.rgb for patch in plan.patches], dtype=float)
    kinds = np.array([patch.kind for patch in plan.patches], dtype=object)
    # the clock: 4 s a patch, up to 40 s more for dark ones (a longer integration)
    clean_Y = display.light(rgb)[:, 1]
    durations = 4.0 + 40.0 * np.exp(-np.maximum(clean_Y, 0) / (0.01 * display.white_Y))
    t = np.cumsum(durations)
    display.session_s = float(t[-1])
    XYZ = display.XYZ(rgb, t)
    effect_free = _Display(np.random.default_rng([seed, 90411]))  # the same draws, no effect
    if probe == "wide-gamut":
        _widen(effect_free, np.random.default_rng([seed, PROBE_STREAM, 0]))
    effect_free_XYZ = effect_free.XYZ(rgb, t)
    gain = a * rng.standard_t(6, len(rgb)) / np.sqrt(6 / 4)
    per_coordinate = 0.3 * a * rng.standard_normal((len(rgb), 3))
    floor = rng.uniform(2e-5, 1e-4) * display.white_Y
    shot = 0.1 * a * np.sqrt(np.abs(XYZ) * display.white_Y) * rng.standard_normal((len(rgb), 3))
    measured = (XYZ * (1 + gain[:, None] + per_coordinate) + shot
                + floor * rng.standard_normal((len(rgb), 3)))
    metadata = {"generator": "independent", "effects": {e: f for e, (f, _) in hidden.items()}}
    if probe == "chromaticity-noise":
        measured = _chromaticity_noise(XYZ, display, a, floor,
                                       np.random.default_rng([seed, PROBE_STREAM, 1]))
    elif probe == "correlated-noise":
        measured = measured + XYZ * _slow_gain(len(rgb), a, np.random.default_rng(
            [seed, PROBE_STREAM, 2]))[:, None]
    if probe is not None:  # a follow-up cannot replay a probe's noise: the floor is kept
        metadata.update(probe=probe, noise_floor=float(floor))
    session = Session(kind=kinds, rgb=rgb, XYZ=measured, t_s=t,
                      source=f"independent generator, seed {seed}, "
                             + (", ".join(f"{e} ({f})" for e, (f, _) in hidden.items()) or "clean")
                             + (f", probe {probe}" if probe else ""),
                      metadata=metadata)
    return GeneratedSession(session=session, effects=hidden, noise=a, true_XYZ=XYZ,
                            effect_free_XYZ=effect_free_XYZ, display=display,
                            effect_free_display=effect_free, plan=plan_name, probe=probe)


# -- a follow-up on the same display ---------------------------------------------------------------
# Appended after the forms: nothing above draws from these streams, so no earlier session changes.

FOLLOW_UP_STREAM = 0xF0110
"""Tag of a follow-up's noise stream: ``[session seed, FOLLOW_UP_STREAM, follow-up seed]``."""


def patch_seconds(display: _Display, rgb) -> np.ndarray:
    """The generator's clock for DAC triplets ``rgb`` (N, 3): 4 s a patch, up to 40 s more for
    dark ones (a longer integration), as :func:`generate_session` times the plan's rows."""
    rgb = np.atleast_2d(np.asarray(rgb, dtype=float))
    clean_Y = display.light(rgb)[:, 1]
    return 4.0 + 40.0 * np.exp(-np.maximum(clean_Y, 0) / (0.01 * display.white_Y))


def _session_seed(generated: GeneratedSession) -> int:
    metadata = generated.session.metadata
    if "generator_seed" in metadata:
        return int(metadata["generator_seed"])
    import re

    match = re.match(r"independent generator, seed (-?\d+)", generated.session.source)
    if match is None:
        raise ValueError(f"not a session of this generator: {generated.session.source!r}")
    return int(match.group(1))


def _noise_floor(generated: GeneratedSession) -> float:
    """The session's noise floor (drawn by :func:`generate_session`, not kept): its stream is
    replayed, and the replay must reproduce the session's measurements bit for bit."""
    metadata = generated.session.metadata
    if "noise_floor" in metadata:
        return float(metadata["noise_floor"])
    seed = _session_seed(generated)
    session, XYZ = generated.session, generated.true_XYZ
    n = len(session)
    for drawn in (True, False):  # the noise drawn from the stream (noise=None) or given
        rng = np.random.default_rng([seed, 90411])
        display = _Display(rng)
        for effect, (form, _) in generated.effects.items():
            _hide(display, effect, form, rng)
        a = float(rng.uniform(0.0005, 0.005)) if drawn else float(generated.noise)
        if a != generated.noise:
            continue
        gain = a * rng.standard_t(6, n) / np.sqrt(6 / 4)
        per_coordinate = 0.3 * a * rng.standard_normal((n, 3))
        floor = rng.uniform(2e-5, 1e-4) * display.white_Y
        shot = 0.1 * a * np.sqrt(np.abs(XYZ) * display.white_Y) * rng.standard_normal((n, 3))
        measured = (XYZ * (1 + gain[:, None] + per_coordinate) + shot
                    + floor * rng.standard_normal((n, 3)))
        if np.array_equal(measured, session.XYZ):
            return float(floor)
    raise ValueError(f"cannot replay the noise of {session.source!r}")


def measure_follow_up(generated: GeneratedSession, patches, seed: int = 0) -> GeneratedSession:
    """Measure ``patches`` (:class:`~workbench.measurement.plans.Patch`, full field) on the same
    display after the session: the session's rows, then the new ones.

    The clock goes on from the session's last row at the generator's own time per patch
    (:func:`patch_seconds`); a drift goes on in time (its form is a function of the time
    since the session began). The noise model is the session's (the same gain noise ``a``
    and floor) on a fresh stream, seeded ``[session seed, FOLLOW_UP_STREAM, seed]``. The
    kinds are the patches' own. The result's truth (``true_XYZ``, ``effect_free_XYZ``)
    covers every row and its :meth:`~GeneratedSession.reference_XYZ` reads the last two
    whites of the combined session; ``session.metadata["follow_ups"]`` lists each follow-up
    (rows, seconds, seed). A follow-up of a follow-up continues the same way.
    """
    patches = list(patches)
    if any(p.window < 1.0 or any(p.surround) for p in patches):
        raise ValueError("the independent generator shows full-field patches only")
    session, display = generated.session, generated.display
    session_seed = _session_seed(generated)
    floor = _noise_floor(generated)
    a = float(generated.noise)
    rgb = np.array([p.rgb for p in patches], dtype=float).reshape(-1, 3)
    kinds = np.array([p.kind for p in patches], dtype=object)
    start = float(np.max(session.t_s))
    durations = patch_seconds(display, rgb) if len(rgb) else np.zeros(0)
    t = start + np.cumsum(durations)
    XYZ = display.XYZ(rgb, t)
    effect_free_XYZ = generated.effect_free_display.XYZ(rgb, t)
    rng = np.random.default_rng([session_seed, FOLLOW_UP_STREAM, int(seed)])
    n = len(rgb)
    gain = a * rng.standard_t(6, n) / np.sqrt(6 / 4)
    per_coordinate = 0.3 * a * rng.standard_normal((n, 3))
    shot = 0.1 * a * np.sqrt(np.abs(XYZ) * display.white_Y) * rng.standard_normal((n, 3))
    measured = (XYZ * (1 + gain[:, None] + per_coordinate) + shot
                + floor * rng.standard_normal((n, 3)))
    window = surround = None
    if session.window is not None or session.surround is not None:
        window = np.concatenate([session.window_or_full, np.ones(n)])
        surround = np.vstack([session.surround_or_black, np.zeros((n, 3))])
    follow_ups = list(session.metadata.get("follow_ups", ())) + [
        {"rows": n, "seconds": float(durations.sum()), "seed": int(seed), "start_s": start}]
    combined = Session(
        kind=np.concatenate([np.asarray(session.kind, dtype=object), kinds]),
        rgb=np.vstack([session.rgb, rgb]), XYZ=np.vstack([session.XYZ, measured]),
        t_s=np.concatenate([session.t_s, t]),
        source=f"{session.source} + follow-up of {n} patches (seed {seed})",
        metadata={**session.metadata, "generator_seed": session_seed, "noise_floor": floor,
                  "follow_ups": follow_ups},
        window=window, surround=surround)
    return GeneratedSession(
        session=combined, effects=generated.effects, noise=generated.noise,
        true_XYZ=np.vstack([generated.true_XYZ, XYZ]),
        effect_free_XYZ=np.vstack([generated.effect_free_XYZ, effect_free_XYZ]),
        display=display, effect_free_display=generated.effect_free_display, plan=generated.plan)


def _measure_more(self: GeneratedSession, patches, seed: int = 0) -> GeneratedSession:
    """``measure_follow_up(self, patches, seed)``: ``patches`` measured on the same display after
    the session (see :func:`measure_follow_up`)."""
    return measure_follow_up(self, patches, seed)


GeneratedSession.measure_more = _measure_more
__all__ += ["FOLLOW_UP_STREAM", "measure_follow_up", "patch_seconds"]
