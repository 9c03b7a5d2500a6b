"""The extended display model: the paper's model plus the terms the diagnostics find.

``XYZ = black + s(load) · Σ_c Y_c · L_c(d_c) · u(xy_c(d_c))``

- ``black``: the XYZ emitted at DAC 0 (black/flare offset; the 3×4 form of the
  matrix model when nothing else is on).
- ``L_c``: per-channel tone curve (:mod:`workbench.display.tone_curves`).
- ``xy_c(d)``: the primary's chromaticity at drive ``d``; constant (the
  full-drive primary) unless level-dependent primaries are on, then
  ``xy_full + a₁(1 − d) + a₂(1 − d)²`` per coordinate, fitted to the
  black-subtracted sweep (Psychtoolbox's multiple primary bases do the same
  job with spectra).
- ``s``: channel interaction, in one of two forms.
  *Per-channel co-drive* (``amounts`` set): each channel's light is scaled by
  ``s_c = 1 − a_c · m^p`` with ``m = (Σ L − max L) / 2`` the light of the
  channels beyond the brightest (0 for a single channel, 1 for white), so
  the sweeps are untouched and the white fixes ``a_c`` exactly in X, Y and Z
  (a chromatic non-additivity: crosstalk, an LCD's dynamic-contrast
  backlight, ``a_c < 0``); ``p`` is chosen on greys where the session has them.
  *Sweeps against the grey ramp* (``axis_ratio`` set; the tone curves then come
  from the grey ramp, as in the seed authors' linearisation): channel ``c``'s
  light is scaled by ``s_c = 1 + (r_c(L_c) − 1)(1 − w_c)``, ``r_c`` the ratio of
  the channel's own sweep to its grey-ramp curve at the same output (measured
  at the sweep levels, interpolated linearly), ``w_c = clip(mean_{o≠c} L_o / L_c,
  0, 1)^q`` how grey the colour is from channel ``c``'s side: 1 on the greys
  (the grey ramp exactly), 0 on the channel's own axis (its sweep exactly);
  ``q`` (``greyness_exponent``) how fast the grey ramp takes over as the other
  channels come up (1: linearly, the form before it was a parameter).
  *Power limit* (``load_weights`` set): one gain for every channel,
  ``s = 1 − a · clip((load − knee)/(1 − knee), 0, 1)^p`` of the
  luminance-weighted load ``Σ w_c L_c`` (a single channel loads the panel by
  its share of the white, so the sweeps carry the limit too; the tone
  curves are then those of the undimmed output).
  *Load knee* (legacy, ``amounts`` None): one gain
  ``s = 1 − a · clip((load − knee)/(1 − knee), 0, 1)``, ``load`` the mean of the
  ``L_c`` (OLED power limiting); ``a < 0`` is super-additivity.
- ``u(x, y) = (x/y, 1, (1 − x − y)/y)``, ``Y_c`` the full-drive luminance.

The inverse iterates (fixed point on the per-channel luminances, 3×3 solve per
step, vectorized) and clips per channel in ``L`` like every model here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from workbench.display.base import DisplayModel, as_dac, as_XYZ
from workbench.display.tone_curves import ToneCurve, tone_curve_from_parameters

__all__ = ["ChromaticityDrift", "ChannelInteraction", "ExtendedDisplay", "xy_to_unit_XYZ"]


def xy_to_unit_XYZ(xy: np.ndarray) -> np.ndarray:
    """XYZ of unit luminance at chromaticity ``xy`` (..., 2)."""
    x, y = xy[..., 0], xy[..., 1]
    return np.stack([x / y, np.ones_like(x), (1.0 - x - y) / y], axis=-1)


@dataclass(frozen=True)
class ChromaticityDrift:
    """``Δxy(d) = a₁ (1 − d) + a₂ (1 − d)²`` for one channel (coefficients (2, 2): [a₁, a₂] × [x, y])."""

    coefficients: tuple[tuple[float, float], tuple[float, float]]

    def delta(self, drive: np.ndarray) -> np.ndarray:
        u = 1.0 - np.clip(drive, 0.0, 1.0)
        a = np.asarray(self.coefficients)
        return u[..., None] * a[0] + (u ** 2)[..., None] * a[1]


@dataclass(frozen=True)
class ChannelInteraction:
    """Channel interaction (module doc): per-channel co-drive gains, or the legacy load knee.

    Attributes
    ----------
    amount : float
        Loss at white in Y (the legacy form's ``a``; for the per-channel form
        the luminance-weighted mean of ``amounts``, for reference).
    knee : float
        Legacy form: the load where the gain starts to fall.
    amounts : tuple of 3 floats, optional
        Per-channel ``a_c`` of the co-drive form.
    exponent : float
        ``p`` of the co-drive form.
    """

    amount: float
    knee: float = 1.0 / 3.0
    amounts: tuple | None = None
    exponent: float = 2.0
    axis_ratio: tuple | None = None
    """Per channel (outputs, ratios): the sweep-to-grey-ramp ratio ``r_c`` at grey-ramp outputs."""
    greyness_exponent: float = 1.0
    """Sweeps-against-the-grey-ramp form: ``q`` in
    ``w_c = clip(mean_{o≠c} L_o / L_c, 0, 1)^q``."""
    load_weights: tuple | None = None
    """Power-limit form: each channel's share of the load (its share of the white's luminance)."""

    def gain(self, load: np.ndarray) -> np.ndarray:
        """Legacy form: the one gain at mean load ``load``."""
        excess = np.clip((load - self.knee) / (1.0 - self.knee), 0.0, 1.0)
        return 1.0 - self.amount * excess

    def channel_gains(self, output: np.ndarray) -> np.ndarray:
        """Gain (..., 3) of each channel's light at channel outputs ``output`` (..., 3)."""
        output = np.clip(output, 0.0, 1.0)
        if self.load_weights is not None:
            load = output @ np.asarray(self.load_weights, dtype=float)
            excess = np.clip((load - self.knee) / (1.0 - self.knee), 0.0, 1.0)
            return np.repeat((1.0 - self.amount * excess ** self.exponent)[..., None], 3, axis=-1)
        if self.axis_ratio is not None:
            gains = np.ones(output.shape)
            for c, (levels, ratios) in enumerate(self.axis_ratio):
                own = output[..., c]
                others = (output.sum(axis=-1) - own) / 2.0
                greyness = np.clip(others / np.maximum(own, 1e-12), 0.0, 1.0) ** \
                    self.greyness_exponent
                ratio = np.interp(own, levels, ratios)
                gains[..., c] = 1.0 + (ratio - 1.0) * (1.0 - greyness)
            return gains
        if self.amounts is None:
            return np.repeat(self.gain(output.mean(axis=-1))[..., None], 3, axis=-1)
        codrive = (output.sum(axis=-1) - output.max(axis=-1)) / 2.0
        return 1.0 - np.asarray(self.amounts) * (codrive ** self.exponent)[..., None]

    def to_json(self) -> dict:
        if self.load_weights is not None:
            return {"amount": self.amount, "knee": self.knee, "exponent": self.exponent,
                    "load_weights": [float(w) for w in self.load_weights]}
        if self.axis_ratio is not None:
            return {"amount": self.amount, "greyness_exponent": float(self.greyness_exponent),
                    "axis_ratio": [{"output": [float(v) for v in levels],
                                    "ratio": [float(v) for v in ratios]}
                                   for levels, ratios in self.axis_ratio]}
        if self.amounts is None:
            return {"amount": self.amount, "knee": self.knee}
        return {"amount": self.amount, "amounts": [float(a) for a in self.amounts],
                "exponent": self.exponent}


@dataclass(frozen=True, eq=False)
class ExtendedDisplay(DisplayModel):
    """The baseline plus found terms (module doc). ``components`` names what is on."""

    black: np.ndarray
    white: np.ndarray
    primaries_xy: np.ndarray  # (3, 2) full-drive, black-subtracted
    primaries_Y: np.ndarray  # (3,)
    tone: tuple[ToneCurve, ToneCurve, ToneCurve]
    chromaticity: tuple[ChromaticityDrift | None, ...] = (None, None, None)
    interaction: ChannelInteraction | None = None
    components: tuple[str, ...] = ()
    iterations: int = field(default=40)

    model_id = "extended"

    def __post_init__(self):
        for name in ("black", "white", "primaries_xy", "primaries_Y"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))

    @property
    def white_XYZ(self):
        return self.white

    @property
    def black_XYZ(self):
        return self.black

    def _xy(self, drive: np.ndarray) -> np.ndarray:
        """Chromaticity (..., 3, 2) of each channel at its drive (..., 3)."""
        xy = np.broadcast_to(self.primaries_xy, drive.shape + (2,)).copy()
        for c, term in enumerate(self.chromaticity):
            if term is not None:
                xy[..., c, :] += term.delta(drive[..., c])
        return xy

    def _luminance_vectors(self, drive: np.ndarray) -> np.ndarray:
        """(..., 3, 3): column c = XYZ per unit normalized output of channel c."""
        unit = xy_to_unit_XYZ(self._xy(drive))  # (..., 3 channels, 3 XYZ)
        return np.swapaxes(unit * self.primaries_Y[:, None], -1, -2)

    def _tone(self, drive: np.ndarray) -> np.ndarray:
        return np.stack([self.tone[c].forward(drive[..., c]) for c in range(3)], axis=-1)

    def _tone_inverse(self, output: np.ndarray) -> np.ndarray:
        return np.stack([self.tone[c].inverse(output[..., c]) for c in range(3)], axis=-1)

    def _gain(self, output: np.ndarray) -> np.ndarray:
        """Gain (..., 3) of each channel's light."""
        if self.interaction is None:
            return np.ones(output.shape)
        return self.interaction.channel_gains(output)

    def forward(self, rgb) -> np.ndarray:
        drive = as_dac(rgb) / 255.0
        output = self._tone(drive)
        vectors = self._luminance_vectors(drive)
        return self.black + np.einsum("...ij,...j->...i", vectors, output * self._gain(output))

    def linear_drive(self, XYZ) -> np.ndarray:
        """Unclipped normalized channel outputs ``L`` that reproduce ``XYZ``."""
        target = as_XYZ(XYZ) - self.black
        drive = np.ones(target.shape[:-1] + (3,))
        output = np.zeros_like(drive)
        simple = self.interaction is None and all(t is None for t in self.chromaticity)
        # a colour whose iteration stops contracting (a gain that changes steeply with output
        # makes it oscillate) takes half steps from then on, halving again each time it does
        step = np.ones(target.shape[:-1] + (1,))
        last_change = np.full(target.shape[:-1] + (1,), np.inf)
        iterations = 1 if simple else self.iterations * (
            3 if self.interaction is not None and self.interaction.axis_ratio is not None else 1)
        for _ in range(iterations):
            vectors = self._luminance_vectors(drive)
            gain = self._gain(np.clip(output, 0.0, 1.0))
            new = np.linalg.solve(vectors, target[..., None])[..., 0] / gain
            if np.allclose(new, output, rtol=0, atol=1e-10):
                output = new
                break
            change = np.max(np.abs(new - output), axis=-1, keepdims=True)
            step = np.where(change >= last_change, 0.5 * step, step)
            last_change = change
            output = output + step * (new - output)
            drive = self._tone_inverse(np.clip(output, 0.0, 1.0))
        return output if simple else self._polish(target, output)

    NEWTON_STEPS = 12
    """Newton steps at most on colours the fixed point left short of their target."""

    def _reproduced(self, output: np.ndarray) -> np.ndarray:
        """XYZ less black of unclipped outputs ``output``, as :meth:`linear_drive` solves for."""
        inside = np.clip(output, 0.0, 1.0)
        vectors = self._luminance_vectors(self._tone_inverse(inside))
        return np.einsum("...ij,...j->...i", vectors, output * self._gain(inside))

    def _polish(self, target: np.ndarray, output: np.ndarray) -> np.ndarray:
        """Newton steps (finite-difference Jacobian, halved until the residual falls) on the
        colours whose residual the fixed point left above 1e-9 of their luminance.

        A gain that changes steeply with the other channels' outputs (the grey ramp's fade near a
        channel's axis) makes the fixed point oscillate; its halved steps then stall short of
        the target. Colours it solved are returned unchanged.
        """
        flat_target = target.reshape(-1, 3)
        flat = output.reshape(-1, 3).copy()
        scale = np.maximum(np.abs(flat_target).max(axis=-1), 1e-12)
        residual = self._reproduced(flat) - flat_target
        for _ in range(self.NEWTON_STEPS):
            norm = np.abs(residual).max(axis=-1)
            open_ = norm > 1e-9 * scale
            if not open_.any():
                break
            here, error = flat[open_], residual[open_]
            step = 1e-7
            jacobian = np.stack([(self._reproduced(here + step * np.eye(3)[k]) - error
                                  - flat_target[open_]) / step for k in range(3)], axis=-1)
            # the pseudo-inverse: a colour whose Jacobian is singular (a clipped channel) takes
            # the least-squares step instead of stopping the others
            delta = (np.linalg.pinv(jacobian) @ -error[..., None])[..., 0]
            best, best_error = here, error
            best_norm = norm[open_]
            for fraction in (1.0, 0.5, 0.25, 0.125):
                trial = here + fraction * delta
                trial_error = self._reproduced(trial) - flat_target[open_]
                trial_norm = np.abs(trial_error).max(axis=-1)
                better = trial_norm < best_norm
                best = np.where(better[:, None], trial, best)
                best_error = np.where(better[:, None], trial_error, best_error)
                best_norm = np.where(better, trial_norm, best_norm)
            flat[open_], residual[open_] = best, best_error
        return flat.reshape(output.shape)

    def dac_from_drive(self, drive) -> np.ndarray:
        return 255.0 * self._tone_inverse(np.asarray(drive, dtype=float))

    def parameters(self) -> dict:
        return {
            "components": list(self.components),
            "black_XYZ": self.black.tolist(),
            "white_XYZ": self.white.tolist(),
            "primaries_xy": self.primaries_xy.tolist(),
            "primaries_Y": self.primaries_Y.tolist(),
            "tone": [curve.to_json() for curve in self.tone],
            "chromaticity": [None if t is None else [list(r) for r in t.coefficients]
                             for t in self.chromaticity],
            "interaction": None if self.interaction is None else self.interaction.to_json(),
        }

    @classmethod
    def from_parameters(cls, parameters: dict) -> "ExtendedDisplay":
        interaction = parameters.get("interaction")
        return cls(
            black=parameters["black_XYZ"], white=parameters["white_XYZ"],
            primaries_xy=parameters["primaries_xy"], primaries_Y=parameters["primaries_Y"],
            tone=tuple(tone_curve_from_parameters(t) for t in parameters["tone"]),
            chromaticity=tuple(None if t is None else ChromaticityDrift(
                tuple(tuple(r) for r in t)) for t in parameters["chromaticity"]),
            interaction=None if interaction is None else ChannelInteraction(**{
                **interaction, **({"amounts": tuple(interaction["amounts"])}
                                  if interaction.get("amounts") is not None else {}),
                **({"load_weights": tuple(interaction["load_weights"])}
                   if interaction.get("load_weights") is not None else {}),
                **({"axis_ratio": tuple((tuple(r["output"]), tuple(r["ratio"]))
                                        for r in interaction["axis_ratio"])}
                   if interaction.get("axis_ratio") is not None else {})}),
            components=tuple(parameters.get("components", ())),
        )

    def describe(self) -> str:
        forms = "/".join(curve.form for curve in self.tone)
        extra = ", ".join(self.components) or "no extensions"
        return f"extended ({extra}; tone {forms})"
