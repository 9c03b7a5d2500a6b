"""3D-LUT residual correction: the general fallback on top of any display model.

``XYZ = base(rgb) + R(rgb)``, where ``R`` is a smooth residual field sampled
on an ``n × n × n`` grid of DAC values and interpolated trilinearly. The grid
is filled from measured mixtures by a smoothing thin-plate radial basis fit of
their residuals (scipy), so it captures whatever the named terms leave behind
(crosstalk patterns, gamut-dependent errors) without a physical story. It
needs mixtures to learn from; :mod:`workbench.diagnostics` fits it by
cross-validation on the validation colours when the session has no other
mixtures, and says so.

The inverse is a fixed-point iteration on the base model's inverse, polished by
Gauss–Newton steps where the fixed point misses a colour the display can show.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RBFInterpolator, RegularGridInterpolator

from workbench.display.base import DisplayModel, as_dac, as_XYZ
from workbench.errors import InputError

__all__ = ["ResidualLUTDisplay", "SMOOTHING_CHOICES", "fit_residual_lut"]

POLISH_GAMUT_MARGIN = 0.01
"""Linear drive by which the fixed point may fall outside [0, 1] and the inverse still look for
the colour itself (:meth:`ResidualLUTDisplay.inverse`): the fixed point's miss near a channel's
zero reads as a drive a little below it."""


@dataclass(frozen=True, eq=False)
class ResidualLUTDisplay(DisplayModel):
    base: DisplayModel
    lut: np.ndarray  # (n, n, n, 3) residual XYZ at the grid nodes
    smoothing: float | None = None  # the RBF smoothing per point it was fitted with (not saved)

    model_id = "lut3d-residual"

    def __post_init__(self):
        lut = np.asarray(self.lut, dtype=float)
        if lut.ndim != 4 or lut.shape[-1] != 3 or len(set(lut.shape[:3])) != 1:
            raise InputError(f"3D-LUT residual must have shape (n, n, n, 3); got {lut.shape}")
        object.__setattr__(self, "lut", lut)
        nodes = np.linspace(0.0, 255.0, lut.shape[0])
        object.__setattr__(self, "_interpolator",
                           RegularGridInterpolator((nodes, nodes, nodes), lut))

    @property
    def white_XYZ(self):
        return self.base.white_XYZ

    @property
    def black_XYZ(self):
        return self.base.black_XYZ

    def residual(self, rgb) -> np.ndarray:
        rgb = as_dac(rgb)
        return self._interpolator(rgb.reshape(-1, 3)).reshape(rgb.shape)

    def forward(self, rgb) -> np.ndarray:
        return self.base.forward(rgb) + self.residual(rgb)

    def _fixed_point(self, XYZ: np.ndarray) -> np.ndarray:
        """DAC of the fixed point ``rgb = base⁻¹(XYZ − R(rgb))``, until it moves < 0.01 count
        (≤ 100 steps)."""
        rgb = self.base.inverse(XYZ)
        for _ in range(100):
            new = self.base.inverse(XYZ - self.residual(rgb))
            converged = np.max(np.abs(new - rgb), initial=0.0) < 0.01
            rgb = new
            if converged:
                break
        return rgb

    def linear_drive(self, XYZ) -> np.ndarray:
        """The base's linear drive for ``XYZ − R(rgb)`` at the fixed point."""
        XYZ = as_XYZ(XYZ)
        return self.base.linear_drive(XYZ - self.residual(self._fixed_point(XYZ)))

    def inverse(self, XYZ) -> np.ndarray:
        """The fixed point's DAC, polished by Gauss–Newton steps where it misses a colour the
        display can show (:meth:`_polish`); out of gamut, clipped as every model's."""
        XYZ = as_XYZ(XYZ)
        drive = self.linear_drive(XYZ)
        clipped = np.clip(drive, 0.0, 1.0)
        dac = self.base.dac_from_drive(clipped)
        # nearly in gamut: where the fixed point's own miss may be all that clipping removed
        near = np.all(np.abs(drive - clipped) < POLISH_GAMUT_MARGIN, axis=-1)
        if np.any(near):
            dac[near] = self._polish(XYZ[near], dac[near])
        return dac

    POLISH_TOLERANCE = 1e-6
    """Largest XYZ miss, relative to the white's Y, that counts as the colour found."""

    def _polish(self, XYZ: np.ndarray, rgb: np.ndarray) -> np.ndarray:
        """Gauss–Newton on ``forward(rgb) = XYZ`` within 0–255 for the rows the fixed point
        misses: each step taken at the fraction (1 down to 1/512) that lowers the miss most, a
        row closed when no fraction does. A row whose colour is not then found within
        :data:`POLISH_TOLERANCE` keeps the fixed point's DAC.

        The fixed point diverges where the base is flat and the residual is not: near a
        channel's zero a power-law tone curve barely moves while the trilinear residual moves in
        proportion to the drive, so each step overshoots (a base whose blue rises as d^2.6
        under a residual linear in blue: colours with 0–3 counts of blue missed by up to 0.115
        ΔE00).
        """
        target = XYZ.reshape(-1, 3)
        start = rgb.reshape(-1, 3).astype(float)
        rgb = start.copy()
        tolerance = self.POLISH_TOLERANCE * float(self.white_XYZ[1])
        step = 0.05  # counts, for the finite-difference Jacobian
        index = np.arange(rgb.shape[0])  # the rows still open
        miss = self.forward(rgb) - target  # each row's, kept as its DAC moves
        for _ in range(30):
            f = miss[index]
            keep = np.abs(f).max(axis=1) > tolerance
            index, f = index[keep], f[keep]
            if not index.size:
                break
            x, goal = rgb[index], target[index]
            jacobian = np.empty(x.shape + (3,))
            for c in range(3):
                h = np.where(x[:, c] + step <= 255.0, step, -step)
                shifted = x.copy()
                shifted[:, c] += h
                jacobian[:, :, c] = (self.forward(shifted) - goal - f) / h[:, None]
            normal = np.einsum("nki,nkj->nij", jacobian, jacobian)
            ridge = 1e-12 * np.einsum("nii->n", normal)[:, None, None] * np.eye(3)
            delta = -np.linalg.solve(normal + ridge,
                                     np.einsum("nki,nk->ni", jacobian, f)[..., None])[..., 0]
            # a flat channel's full step overshoots, and the box 0–255 cuts it
            best, best_f, best_cost = x, f, np.sum(f ** 2, axis=1)
            for fraction in 0.5 ** np.arange(10):
                trial = np.clip(x + fraction * delta, 0.0, 255.0)
                trial_f = self.forward(trial) - goal
                cost = np.sum(trial_f ** 2, axis=1)
                take = cost < best_cost
                best = np.where(take[:, None], trial, best)
                best_f = np.where(take[:, None], trial_f, best_f)
                best_cost = np.where(take, cost, best_cost)
            rgb[index], miss[index] = best, best_f
            index = index[np.any(best != x, axis=1)]
        found = np.abs(miss).max(axis=1) <= tolerance
        return np.where(found[:, None], rgb, start).reshape(XYZ.shape)

    def dac_from_drive(self, drive) -> np.ndarray:
        return self.base.dac_from_drive(drive)

    def parameters(self) -> dict:
        return {"base_type": self.base.model_id, "base": self.base.parameters(),
                "lut_size": int(self.lut.shape[0]), "lut": self.lut.reshape(-1, 3).tolist()}

    @classmethod
    def from_parameters(cls, parameters: dict) -> "ResidualLUTDisplay":
        from workbench.display import display_model_from_parameters

        size = int(parameters["lut_size"])
        return cls(base=display_model_from_parameters(parameters["base_type"], parameters["base"]),
                   lut=np.asarray(parameters["lut"], dtype=float).reshape(size, size, size, 3))

    def describe(self) -> str:
        return f"{self.base.describe()} + {self.lut.shape[0]}³ residual LUT"


SMOOTHING_CHOICES = (0.003, 0.01, 0.03, 0.1, 0.3)
"""RBF smoothing per training point tried by the inner cross-validation."""


def _choose_smoothing(rgb: np.ndarray, residual: np.ndarray, folds: int = 4) -> float:
    """Smoothing (per point) with the lowest inner cross-validated squared error."""
    order = np.random.default_rng(0).permutation(len(rgb)) % folds
    errors = []
    for per_point in SMOOTHING_CHOICES:
        total = 0.0
        for k in range(folds):
            train = order != k
            field = RBFInterpolator(rgb[train] / 255.0, residual[train], kernel="thin_plate_spline",
                                    smoothing=per_point * train.sum())
            total += float(np.sum((field(rgb[~train] / 255.0) - residual[~train]) ** 2))
        errors.append(total)
    return SMOOTHING_CHOICES[int(np.argmin(errors))]


def fit_residual_lut(base: DisplayModel, rgb, XYZ, *, size: int = 9,
                     smoothing: float | None = None) -> ResidualLUTDisplay:
    """Fit the residual field of ``base`` on measured mixtures ``(rgb, XYZ)``.

    ``smoothing`` is the thin-plate RBF smoothing per training point; by
    default it is chosen by an inner 4-fold cross-validation on these mixtures
    among :data:`SMOOTHING_CHOICES`.
    """
    rgb = as_dac(rgb).reshape(-1, 3)
    XYZ = as_XYZ(XYZ).reshape(-1, 3)
    if len(rgb) < 10:
        raise InputError(f"a residual LUT needs at least 10 measured mixtures; got {len(rgb)}")
    residual = XYZ - base.forward(rgb)
    if smoothing is None:
        smoothing = _choose_smoothing(rgb, residual)
    field = RBFInterpolator(rgb / 255.0, residual, kernel="thin_plate_spline",
                            smoothing=smoothing * len(rgb))
    nodes = np.linspace(0.0, 1.0, size)
    grid = np.stack(np.meshgrid(nodes, nodes, nodes, indexing="ij"), axis=-1).reshape(-1, 3)
    return ResidualLUTDisplay(base=base, lut=field(grid).reshape(size, size, size, 3),
                              smoothing=float(smoothing))
