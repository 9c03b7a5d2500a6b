"""The paper's display model: per-channel gamma, then a 3×3 matrix (Eq. 1–2).

``L_c = d_c ** γ_c`` with ``d = DAC / 255``, then ``XYZ = M · [L_r, L_g, L_b]``;
the columns of ``M`` are the measured XYZ of the full-drive primaries and
``γ_c`` is fitted to that channel's sweep luminance normalized by its maximum.
There is no black term: this is the *baseline* every diagnosis reports against.

References
----------
Díaz-Barrancas, F., Cwierz, H., Pardo, P. J., Pérez, Á. L., & Suero, M. I.
(2020). Spectral Color Management in Virtual Reality Scenes. Sensors, 20(19),
5658, §2.1, Eq. (1)–(2), Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from workbench.display.base import DisplayModel, as_dac
from workbench.display.tone_curves import noise_weights
from workbench.errors import InputError
from workbench.session import Session

__all__ = ["GammaMatrixDisplay", "fit_power_law", "GAMMA_WEIGHTINGS", "RAMP_KINDS"]

RAMP_KINDS = ("ramp-r", "ramp-g", "ramp-b")


GAMMA_WEIGHTINGS = {
    "luminance": "least squares in normalized luminance (the paper's fit: the bright levels "
                 "weigh most)",
    "noise": "least squares weighted by one over the instrument's noise (relative, with a floor "
             "in the dark: every level weighs by how well it is measured)",
}
"""How :func:`fit_power_law` weighs the sweep levels."""


def fit_power_law(drive: np.ndarray, response: np.ndarray, weighting: str = "luminance"
                  ) -> tuple[float, float]:
    """Least-squares ``γ`` of ``response = drive ** γ`` and the fit's R².

    ``drive`` on (0, 1], ``response`` normalized so that full drive is 1;
    ``weighting`` one of :data:`GAMMA_WEIGHTINGS`. A spectroradiometer's
    noise is relative, so the ``"noise"`` weighting is the maximum-likelihood
    ``γ`` where the power law holds: in luminance a few bright levels decide
    it, and with ten sweep levels at 0.3 % noise a blue γ came out 2.535 for
    2.517, which puts 5 % on its dark end.
    """
    if weighting not in GAMMA_WEIGHTINGS:
        raise InputError(f"unknown gamma weighting {weighting!r}; use one of "
                         f"{', '.join(GAMMA_WEIGHTINGS)}")
    drive = np.asarray(drive, dtype=float)
    response = np.asarray(response, dtype=float)
    keep = drive > 0
    if keep.sum() < 2:
        raise InputError("a power-law fit needs at least two sweep levels above DAC 0")
    drive, response = drive[keep], response[keep]
    weight = noise_weights(response) if weighting == "noise" else np.ones_like(response)
    gamma = _least_squares_exponent(drive, response, weight)
    residual = drive ** gamma - response
    total = np.sum((response - response.mean()) ** 2)
    r_squared = float(1 - np.sum(residual ** 2) / total) if total > 0 else 1.0
    return gamma, r_squared


GAMMA_BOUNDS = (0.1, 10.0)
"""The exponents :func:`fit_power_law` searches between."""


def _least_squares_exponent(drive: np.ndarray, response: np.ndarray, weight: np.ndarray,
                            start: float = 2.2) -> float:
    """The ``γ`` in :data:`GAMMA_BOUNDS` of least ``Σ (w·(dᵞ − r))²``, by Newton's method from
    ``start``: the step of the objective's second derivative where it is positive (its
    Gauss–Newton part where not), halved until the sum of squares falls, held to the bounds.

    One parameter and a closed-form derivative: about six iterations of a vectorised sum, where
    ``scipy.optimize.least_squares`` (trust-region reflective, derivative by finite differences)
    took 5 ms a fit, a quarter of a diagnosis (a session's every fold refits three sweeps). The
    same local minimum from the same start, to its tolerance (where that minimum lies in a flat
    valley, as on a sweep with a shoulder, the lower sum of squares that scipy's tolerances stop
    short of). On the diagnosis suite's 940 sessions every finding and model is the same, no
    score moved by more than 2·10⁻⁴ (with the tone test's closed-form Jacobian, 0.57 → 0.51 s a
    session, run side by side); the peer bench's 636 drift sessions, the six real files and
    the 76 public charts: the same findings, no hidden-colour score moved by more than
    4·10⁻⁵ ΔE00.
    """
    log_drive = np.log(drive)
    low, high = GAMMA_BOUNDS

    def state(gamma):
        power = drive ** gamma
        residual = weight * (power - response)
        jacobian = weight * power * log_drive
        return float(residual @ residual), residual, jacobian, power

    gamma = float(np.clip(start, low, high))
    cost, residual, jacobian, power = state(gamma)
    for _ in range(100):
        gradient = float(residual @ jacobian)
        gauss_newton = float(jacobian @ jacobian)
        if gauss_newton <= 0.0 or gradient == 0.0:
            break
        curvature = gauss_newton + float(residual @ (weight * power * log_drive ** 2))
        step = -gradient / (curvature if curvature > 0.0 else gauss_newton)
        target = float(np.clip(gamma + step, low, high))
        if target == gamma:
            break  # at a bound, the slope pointing out of it
        for _ in range(60):
            trial = state(target)
            if trial[0] <= cost:
                break
            target = 0.5 * (gamma + target)
        else:
            break  # no step along the slope lowers the sum of squares
        previous, gamma = gamma, target
        cost, residual, jacobian, power = trial
        if abs(gamma - previous) <= 1e-12 * max(1.0, abs(gamma)):
            break
    return gamma


def _channel_sweep(session: Session, channel: int) -> tuple[np.ndarray, np.ndarray]:
    """DAC levels and XYZ of one channel's sweep (other channels at 0)."""
    others = [c for c in range(3) if c != channel]
    rows = (session.mask(RAMP_KINDS[channel]) & np.all(session.rgb[:, others] == 0, axis=1)
            & (session.rgb[:, channel] > 0))
    return session.rgb[rows, channel], session.XYZ[rows]


@dataclass(frozen=True, eq=False)
class GammaMatrixDisplay(DisplayModel):
    """Per-channel power law + 3×3 matrix (the paper's model).

    Attributes
    ----------
    gamma : ndarray (3,)
    matrix : ndarray (3, 3)
        Columns: XYZ of the red, green and blue primaries at full drive.
    white : ndarray (3,)
        Measured white XYZ (``Y_white`` of relative colorimetry).
    black : ndarray (3,)
        Measured black XYZ, kept for reference; the model does not use it.
    r_squared : ndarray (3,)
        R² of each channel's gamma fit (NaN where not fitted from data).
    """

    gamma: np.ndarray
    matrix: np.ndarray
    white: np.ndarray
    black: np.ndarray = field(default_factory=lambda: np.zeros(3))
    r_squared: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))

    model_id = "gamma-matrix"

    def __post_init__(self):
        for name, shape in (("gamma", (3,)), ("matrix", (3, 3)), ("white", (3,)),
                            ("black", (3,)), ("r_squared", (3,))):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != shape:
                raise InputError(f"gamma-matrix display: {name} must have shape {shape}, "
                                 f"got {value.shape}")
            object.__setattr__(self, name, value)
        if np.any(self.gamma <= 0) or not np.all(np.isfinite(self.gamma)):
            raise InputError(f"gamma-matrix display: gammas must be positive; got {self.gamma}")
        if abs(np.linalg.det(self.matrix)) < 1e-12 * max(1.0, np.abs(self.matrix).max()) ** 3:
            raise InputError("gamma-matrix display: the primaries matrix is singular "
                             "(two primaries have the same chromaticity?)")
        object.__setattr__(self, "_inverse_matrix", np.linalg.inv(self.matrix))

    @property
    def white_XYZ(self) -> np.ndarray:
        return self.white

    @property
    def black_XYZ(self) -> np.ndarray:
        return self.black

    def forward(self, rgb) -> np.ndarray:
        drive = (as_dac(rgb) / 255.0) ** self.gamma
        return drive @ self.matrix.T

    def linear_drive(self, XYZ) -> np.ndarray:
        return np.asarray(XYZ, dtype=float) @ self._inverse_matrix.T

    def dac_from_drive(self, drive) -> np.ndarray:
        return 255.0 * np.asarray(drive, dtype=float) ** (1.0 / self.gamma)

    def parameters(self) -> dict:
        return {
            "gamma": self.gamma.tolist(),
            "matrix": self.matrix.tolist(),
            "white_XYZ": self.white.tolist(),
            "black_XYZ": self.black.tolist(),
            "r_squared": [None if np.isnan(v) else float(v) for v in self.r_squared],
        }

    @classmethod
    def from_parameters(cls, parameters: dict) -> "GammaMatrixDisplay":
        return cls(
            gamma=parameters["gamma"],
            matrix=parameters["matrix"],
            white=parameters["white_XYZ"],
            black=parameters.get("black_XYZ", [0.0, 0.0, 0.0]),
            r_squared=[np.nan if v is None else v
                       for v in parameters.get("r_squared", [None] * 3)],
        )

    @classmethod
    def from_primaries_xyY(cls, primaries_xyY, white_xyY, gamma, black_xyY=None
                           ) -> "GammaMatrixDisplay":
        """Build the model from published chromaticities and luminances (e.g. Table 1)."""
        def xyY_to_XYZ(xyY):
            x, y, Y = np.asarray(xyY, dtype=float)
            return np.array([x / y * Y, Y, (1 - x - y) / y * Y])

        matrix = np.column_stack([xyY_to_XYZ(p) for p in primaries_xyY])
        black = np.zeros(3) if black_xyY is None else xyY_to_XYZ(black_xyY)
        return cls(gamma=gamma, matrix=matrix, white=xyY_to_XYZ(white_xyY), black=black)

    @classmethod
    def fit(cls, session: Session, weighting: str = "luminance") -> "GammaMatrixDisplay":
        """Fit from a session's black, white and per-channel sweeps (never its validation rows).

        ``weighting``: how each γ weighs the sweep levels (:data:`GAMMA_WEIGHTINGS`); the
        baseline is the paper's, in luminance.
        """
        gammas, r_squared, columns = [], [], []
        for channel, kind in enumerate(RAMP_KINDS):
            levels, XYZ = _channel_sweep(session, channel)
            if len(levels) == 0:
                raise InputError(f"session {session.source!r} has no {kind} sweep; the paper's model "
                                 "needs a sweep of each channel (measure plan 'paper' or 'quick')")
            full = levels >= levels.max()
            if levels.max() < 255:
                raise InputError(f"session {session.source!r}: the {kind} sweep stops at DAC "
                                 f"{levels.max():g}; the model needs the full-drive (255) primary")
            columns.append(XYZ[full].mean(axis=0))
            if np.sum(levels > 0) < 2:
                raise InputError(f"session {session.source!r}: the {kind} sweep has only "
                                 f"{int(np.sum(levels > 0))} level above DAC 0; fitting its gamma "
                                 "needs at least two (measure the 'paper' or 'quick' plan)")
            gamma, r2 = fit_power_law(levels / 255.0, XYZ[:, 1] / columns[-1][1], weighting)
            gammas.append(gamma)
            r_squared.append(r2)
        matrix = np.column_stack(columns)
        # ramps-only data (e.g. Psychtoolbox): the white is the additive one the model predicts
        white = session.white_XYZ if session.has_white else matrix.sum(axis=1)
        return cls(gamma=gammas, matrix=matrix, white=white, black=session.black_XYZ,
                   r_squared=r_squared)

    def describe(self) -> str:
        return "gamma-matrix (γ = " + ", ".join(f"{g:.2f}" for g in self.gamma) + ")"

