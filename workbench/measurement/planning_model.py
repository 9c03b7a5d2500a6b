"""The adaptive plan's surrogate: how well the rows measured so far predict unseen colours.

:class:`PlanningModel` is fitted on the fit rows of a session in progress
(never its validation rows) and predicts, for colours spread over the whole
8-bit cube (the *planning colours*: a seeded quasi-random set that stands for
the held-out colours and is never measured), the ΔE00 a model of these rows
would make on them, and how much measuring one more patch would lower that.
It is not the profile's model (the diagnosis exports that,
:func:`workbench.diagnostics.diagnose`); it is the part of it that says what
is still unknown:

* **each channel's tone curve** (luminance), as a Gaussian process over
  ``u = ln(drive)`` of ``z = ln(output / full-drive output)``, with a
  power law's slope as a term of its kernel (a prior slope 2.2 ± 1) plus a
  smooth departure (squared-exponential, amplitude and length by maximum
  marginal likelihood on a grid). The sweep points are its data, each with
  the variance the session's noise model gives it at its luminance;
* **how the channels combine** away from the sweeps: the departure of each
  grey, mixture and white from the additive prediction of its channels
  (``ρ = (XYZ − Σ_c P_c y_c) / Y_additive``), as a Gaussian process over the
  mean drive (a load) and the co-drive ``s(d) = (Σd − max d) / 2`` (the
  quantities the diagnosis's interaction models depend on: a power limit's
  load, a crosstalk's co-drive), whose kernel vanishes where at most one
  channel is lit (it is scaled by ``s``), amplitude and length by maximum
  marginal likelihood, with each row's variance from the noise model plus
  the tone curves' own uncertainty there;
* **the full-drive primaries**, each known to the session's gain noise over
  the square root of the times it was measured.

Rows are first divided by the drift of the white references (linear in time
between them), as a drift correction does. Each source of uncertainty is
carried to ΔE00 at each planning colour through the local sensitivity of
CIEDE2000 (CIELAB white: the measured white), and the predicted held-out
ΔE00 is the mean over the planning colours of ``√(2/π) · √(Σ_k e_k²)`` (the
mean size of an error whose parts are independent and normal). A candidate
patch lowers the posterior variance of its process in closed form (a
Gaussian process's variance does not depend on the value that will be
measured), so the expected reduction of every candidate is exact under the
surrogate, and a deterministic function of the rows measured.

Units: XYZ in the session's units (cd/m²), drives 0..1, DAC 0..255.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.colorimetry import delta_E2000

__all__ = ["PRIOR_GAMMA", "PRIOR_GAMMA_SD", "MEAN_ABS_FACTOR", "PlanningRows", "PlanningModel",
           "planning_colours"]

PRIOR_GAMMA = 2.2
"""Prior mean of a tone curve's log-log slope."""
PRIOR_GAMMA_SD = 1.0
"""Prior standard deviation of that slope."""
MEAN_ABS_FACTOR = float(np.sqrt(2.0 / np.pi))
"""Mean absolute value of a unit normal error: turns a standard deviation into an expected error."""

_TONE_LENGTHS = (0.5, 1.0, 2.0)  # in ln(drive)
_MIX_LENGTHS = (0.15, 0.3, 0.6)  # in mean drive and co-drive
_AMPLITUDES = tuple(0.0005 * 2.0 ** k for k in range(12))  # 0.05 % … 100 %
_STEP = 1e-3  # relative perturbation for the ΔE00 sensitivities
_MIN_OUTPUT = 1e-5  # outputs below this share of full drive are dark: ln stays finite


def planning_colours(seed: int, count: int = 256) -> np.ndarray:
    """``count`` seeded DAC triplets uniform over the cube, a stream no plan measures."""
    return np.random.default_rng([int(seed), 0xADA97]).integers(0, 256, size=(count, 3)).astype(float)


@dataclass(frozen=True)
class PlanningRows:
    """The fit rows the surrogate reads: DAC values, XYZ (drift-divided) and kinds."""

    rgb: np.ndarray
    XYZ: np.ndarray
    kind: np.ndarray

    @property
    def lit(self) -> np.ndarray:
        return (self.rgb > 0).sum(axis=1)


def _rbf(a, b, length):
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    squared = ((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2)
    return np.exp(-squared / (2.0 * length ** 2))


class _GaussianProcess:
    """Posterior of a zero-mean Gaussian process with a given kernel and per-point noise."""

    def __init__(self, kernel, X, y, noise_var):
        self.kernel, self.X = kernel, X
        self.y = np.asarray(y, dtype=float).reshape(len(X), -1)
        K = kernel(X, X) + np.diag(np.maximum(noise_var, 1e-14))
        self.chol = np.linalg.cholesky(K + 1e-12 * np.eye(len(X)))
        self.weights = _solve(self.chol, self.y)

    @staticmethod
    def log_marginal(kernel, X, y, noise_var) -> float:
        y = np.asarray(y, dtype=float).reshape(len(X), -1)
        K = kernel(X, X) + np.diag(np.maximum(noise_var, 1e-14))
        try:
            chol = np.linalg.cholesky(K + 1e-12 * np.eye(len(X)))
        except np.linalg.LinAlgError:
            return -np.inf
        w = _solve(chol, y)
        return float(-0.5 * np.sum(y * w) - y.shape[1] * np.sum(np.log(np.diag(chol))))

    def mean(self, U) -> np.ndarray:
        return self.kernel(U, self.X) @ self.weights

    def _projected(self, U):
        return np.linalg.solve(self.chol, self.kernel(self.X, U))

    def variance(self, U, prior_diag) -> np.ndarray:
        V = self._projected(U)
        return np.maximum(prior_diag - np.sum(V * V, axis=0), 0.0)

    def covariance(self, U, C) -> np.ndarray:
        """Posterior covariance between ``U`` (rows) and ``C`` (columns)."""
        return self.kernel(U, C) - self._projected(U).T @ self._projected(C)


def _solve(chol, y):
    return np.linalg.solve(chol.T, np.linalg.solve(chol, y))


def _fit_gp(make_kernel, X, y, noise_var, grid):
    """The process whose hyperparameters (from ``grid``) maximise the marginal likelihood."""
    best = None
    for params in grid:
        value = _GaussianProcess.log_marginal(make_kernel(*params), X, y, noise_var)
        if best is None or value > best[0] + 1e-9:
            best = (value, params)
    kernel = make_kernel(*best[1])
    return _GaussianProcess(kernel, X, y, noise_var), best[1]


class PlanningModel:
    """The surrogate of the module doc, fitted on ``rows``.

    Parameters
    ----------
    rows : PlanningRows
        Fit rows, drift-divided; must hold a black, a white and each
        primary at full drive.
    relative_sd : callable
        ``relative_sd(Y)``: one measurement's relative luminance noise at
        ``Y`` (the session's noise model).
    gain_sd : float
        One measurement's gain noise (relative), for the primaries.
    planning_rgb : ndarray (N, 3)
        The planning colours (:func:`planning_colours`).
    """

    def __init__(self, rows: PlanningRows, relative_sd, gain_sd: float, planning_rgb: np.ndarray):
        self.rows, self.relative_sd, self.gain_sd = rows, relative_sd, float(gain_sd)
        rgb, XYZ = rows.rgb, rows.XYZ
        black = np.all(rgb == 0, axis=1)
        white = np.all(rgb >= 255, axis=1)
        if not black.any() or not white.any():
            raise ValueError("the planning model needs a black and a white")
        self.black = XYZ[black].mean(axis=0)
        self.white = XYZ[white].mean(axis=0)
        self.primaries = np.zeros((3, 3))  # columns: full-drive primary minus black
        self.primary_count = np.zeros(3)
        self.tone: list = []
        self.tone_params: list = []
        for c in range(3):
            own = (rows.lit == 1) & (rgb[:, c] > 0)
            full = own & (rgb[:, c] >= 255)
            if not full.any():
                raise ValueError(f"the planning model needs channel {c} at full drive")
            self.primaries[:, c] = XYZ[full].mean(axis=0) - self.black
            self.primary_count[c] = full.sum()
            partial = own & (rgb[:, c] < 255)
            d = rgb[partial, c] / 255.0
            Y = XYZ[partial, 1]
            P_Y = self.primaries[1, c]
            y = (Y - self.black[1]) / P_Y
            sd = self.relative_sd(Y) * np.abs(Y) / P_Y
            z = np.log(np.maximum(y, _MIN_OUTPUT))
            sd_z = np.where(y > _MIN_OUTPUT, sd / np.maximum(y, _MIN_OUTPUT), 10.0)
            u = np.append(np.log(d), 0.0)[:, None]  # full drive: z = 0 by definition
            target = np.append(z, 0.0) - PRIOR_GAMMA * u[:, 0]
            noise = np.append(sd_z ** 2, 1e-10)
            gp, params = _fit_gp(self._tone_kernel, u, target, noise,
                                 [(a, ell) for a in _AMPLITUDES for ell in _TONE_LENGTHS])
            self.tone.append(gp)
            self.tone_params.append(params)
        self.planning_rgb = np.asarray(planning_rgb, dtype=float)
        self._fit_mixing()
        self._prepare_planning()

    # -- tone curves ----------------------------------------------------------------------------
    @staticmethod
    def _tone_kernel(amplitude, length):
        def kernel(a, b):
            return PRIOR_GAMMA_SD ** 2 * (a @ b.T) + amplitude ** 2 * _rbf(a, b, length)
        return kernel

    def _tone_prior_var(self, c, u):
        amplitude, _ = self.tone_params[c]
        return PRIOR_GAMMA_SD ** 2 * u[:, 0] ** 2 + amplitude ** 2

    def outputs(self, rgb) -> np.ndarray:
        """Each channel's output (share of its full-drive output) at ``rgb`` (N, 3), posterior mean."""
        d = np.clip(np.asarray(rgb, dtype=float) / 255.0, 0.0, 1.0)
        out = np.zeros(d.shape)
        for c in range(3):
            on = d[:, c] > 0
            if on.any():
                u = np.log(d[on, c])[:, None]
                out[on, c] = np.exp(PRIOR_GAMMA * u[:, 0] + self.tone[c].mean(u)[:, 0])
        return out

    def tone_sd(self, rgb) -> np.ndarray:
        """Posterior SD of ``ln`` output per channel at ``rgb`` (0 where a channel is off)."""
        d = np.clip(np.asarray(rgb, dtype=float) / 255.0, 0.0, 1.0)
        sd = np.zeros(d.shape)
        for c in range(3):
            on = d[:, c] > 0
            if on.any():
                u = np.log(d[on, c])[:, None]
                sd[on, c] = np.sqrt(self.tone[c].variance(u, self._tone_prior_var(c, u)))
        return sd

    def additive(self, rgb) -> np.ndarray:
        """XYZ of ``rgb`` as the sum of its channels' outputs (black included)."""
        return self.black + self.outputs(rgb) @ self.primaries.T

    # -- how the channels combine ---------------------------------------------------------------
    @staticmethod
    def _codrive(x):
        return (x.sum(axis=1) - x.max(axis=1)) / 2.0

    @classmethod
    def _features(cls, x):
        """Where a departure from additivity is read: the mean drive (a load) and the co-drive."""
        return np.column_stack([x.mean(axis=1), cls._codrive(x)])

    @classmethod
    def _mix_kernel(cls, amplitude, length):
        def kernel(a, b):
            return (amplitude ** 2 * np.outer(cls._codrive(a), cls._codrive(b))
                    * _rbf(cls._features(a), cls._features(b), length))
        return kernel

    def _fit_mixing(self):
        rows = self.rows
        mixed = rows.lit >= 2
        self.mix_x = rows.rgb[mixed] / 255.0
        if not mixed.any():
            self.mixing, self.mix_params = None, (_AMPLITUDES[0], _MIX_LENGTHS[1])
            return
        predicted = self.additive(rows.rgb[mixed])
        Y = np.maximum(predicted[:, 1], 1e-12)
        rho = (rows.XYZ[mixed] - predicted) / Y[:, None]
        share = self.outputs(rows.rgb[mixed]) * self.primaries[1] / Y[:, None]
        tone_var = np.sum((share * self.tone_sd(rows.rgb[mixed])) ** 2, axis=1)
        noise = self.relative_sd(rows.XYZ[mixed, 1]) ** 2 + tone_var
        floor = max(self.gain_sd, _AMPLITUDES[0])
        grid = [(a, ell) for a in _AMPLITUDES if a >= floor / 2 for ell in _MIX_LENGTHS]
        self.mixing, self.mix_params = _fit_gp(self._mix_kernel, self.mix_x, rho, noise, grid)
        self.mix_noise = noise
        self.mix_residual = rho

    def mixing_sd(self, rgb) -> np.ndarray:
        """Posterior SD of the relative departure from additivity at ``rgb``."""
        x = np.asarray(rgb, dtype=float) / 255.0
        amplitude, _ = self.mix_params
        prior = amplitude ** 2 * self._codrive(x) ** 2
        if self.mixing is None:
            return np.sqrt(prior)
        return np.sqrt(self.mixing.variance(x, prior))

    def predict(self, rgb) -> np.ndarray:
        """XYZ of ``rgb``: additive, corrected by the posterior mean of the departure."""
        rgb = np.atleast_2d(np.asarray(rgb, dtype=float))
        additive = self.additive(rgb)
        if self.mixing is None:
            return additive
        return additive + np.maximum(additive[:, 1:2], 0.0) * self.mixing.mean(rgb / 255.0)

    def largest_departure(self) -> float:
        """The largest measured relative departure from additivity (Y), 0 without mixtures."""
        if self.mixing is None:
            return 0.0
        return float(np.max(np.abs(self.mix_residual[:, 1])))

    # -- predicted held-out error ---------------------------------------------------------------
    def _prepare_planning(self):
        P = self.planning_rgb
        self.plan_XYZ = self.predict(P)
        self.plan_outputs = self.outputs(P)
        reference = self.white
        base = self.plan_XYZ
        # ΔE00 per unit relative change of each channel's light, and per unit relative
        # departure in X, Y and Z (of the colour's additive luminance)
        sensitivity = []
        for c in range(3):
            delta = np.outer(self.plan_outputs[:, c], self.primaries[:, c]) * _STEP
            sensitivity.append(delta_E2000(base + delta, base, reference) / _STEP)
        Y = np.maximum(self.additive(P)[:, 1], 0.0)
        for k in range(3):
            delta = np.zeros_like(base)
            delta[:, k] = Y * _STEP
            sensitivity.append(delta_E2000(base + delta, base, reference) / _STEP)
        self.sensitivity = np.nan_to_num(np.column_stack(sensitivity))
        self.plan_u = [np.log(np.maximum(P[:, c], 1.0) / 255.0)[:, None] for c in range(3)]
        self.plan_tone_var = np.column_stack([
            self.tone[c].variance(self.plan_u[c], self._tone_prior_var(c, self.plan_u[c]))
            for c in range(3)]) * (P > 0)
        self.plan_mix_var = self.mixing_sd(P) ** 2

    def _error(self, tone_var, mix_var, primary_var) -> np.ndarray:
        """Predicted mean ΔE00 over the planning colours for the given variances.

        ``tone_var`` (N, 3) or (M, N, 3), ``mix_var`` (N,) or (M, N), ``primary_var`` (3,)
        or (M, 3); the result has the leading M where any has it.
        """
        S = self.sensitivity
        tone = (tone_var + primary_var[..., None, :]) * S[:, :3] ** 2
        mix = mix_var[..., None] * S[:, 3:] ** 2
        total = tone.sum(axis=-1) + mix.sum(axis=-1)
        return MEAN_ABS_FACTOR * np.sqrt(total).mean(axis=-1)

    def primary_var(self, counts=None) -> np.ndarray:
        counts = self.primary_count if counts is None else counts
        return self.gain_sd ** 2 / counts

    def predicted_error(self) -> float:
        """Predicted held-out mean ΔE00 of a model of the rows so far (module doc)."""
        return float(self._error(self.plan_tone_var, self.plan_mix_var, self.primary_var()))

    def error_parts(self) -> dict:
        """The predicted error with one source at a time (the others' variance set to 0)."""
        zeros3, zerosN = np.zeros_like(self.plan_tone_var), np.zeros_like(self.plan_mix_var)
        parts = {}
        for c, name in enumerate(("red tone curve", "green tone curve", "blue tone curve")):
            only = zeros3.copy()
            only[:, c] = self.plan_tone_var[:, c]
            parts[name] = float(self._error(only, zerosN, np.zeros(3)))
        parts["channel interaction"] = float(self._error(zeros3, self.plan_mix_var, np.zeros(3)))
        parts["primaries (noise)"] = float(self._error(zeros3, zerosN, self.primary_var()))
        return parts

    # -- what a patch would buy -----------------------------------------------------------------
    def after_sweep_levels(self, channel: int, dac) -> np.ndarray:
        """Predicted error after measuring each of ``dac`` (M,) on ``channel`` alone."""
        dac = np.asarray(dac, dtype=float)
        u = np.log(dac / 255.0)[:, None]
        gp = self.tone[channel]
        rgb = np.zeros((len(dac), 3))
        rgb[:, channel] = dac
        Y = self.additive(rgb)[:, 1]
        y = np.maximum(self.outputs(rgb)[:, channel], _MIN_OUTPUT)
        noise = (self.relative_sd(Y) * np.abs(Y) / self.primaries[1, channel] / y) ** 2
        cov = gp.covariance(self.plan_u[channel], u)  # (N, M)
        var_c = gp.variance(u, self._tone_prior_var(channel, u)) + noise
        tone_var = np.repeat(self.plan_tone_var[None], len(dac), axis=0)
        on = self.planning_rgb[:, channel] > 0
        reduced = self.plan_tone_var[:, channel][None, :] - (cov.T ** 2) / var_c[:, None]
        tone_var[:, :, channel] = np.where(on[None, :], np.maximum(reduced, 0.0), 0.0)
        mix = np.repeat(self.plan_mix_var[None], len(dac), axis=0)
        return self._error(tone_var, mix, np.repeat(self.primary_var()[None], len(dac), axis=0))

    def after_mixtures(self, rgb) -> np.ndarray:
        """Predicted error after measuring each of ``rgb`` (M, 3), a grey or mixture."""
        rgb = np.atleast_2d(np.asarray(rgb, dtype=float))
        x = rgb / 255.0
        amplitude, _ = self.mix_params
        prior_plan = amplitude ** 2 * self._codrive(self.planning_rgb / 255.0) ** 2
        prior_cand = amplitude ** 2 * self._codrive(x) ** 2
        Xp = self.planning_rgb / 255.0
        if self.mixing is None:
            kernel = self._mix_kernel(*self.mix_params)
            cov = kernel(Xp, x)
            var_c = prior_cand.copy()
        else:
            cov = self.mixing.covariance(Xp, x)
            var_c = self.mixing.variance(x, prior_cand)
        predicted = self.predict(rgb)
        Y = np.maximum(predicted[:, 1], 1e-12)
        share = self.outputs(rgb) * self.primaries[1] / Y[:, None]
        noise = self.relative_sd(Y) ** 2 + np.sum((share * self.tone_sd(rgb)) ** 2, axis=1)
        mix = np.maximum(self.plan_mix_var[None, :] - (cov.T ** 2) / (var_c + noise)[:, None], 0.0)
        del prior_plan
        M = len(rgb)
        return self._error(np.repeat(self.plan_tone_var[None], M, axis=0), mix,
                           np.repeat(self.primary_var()[None], M, axis=0))

    def after_primary(self, channel: int) -> float:
        """Predicted error after measuring ``channel`` at full drive once more."""
        counts = self.primary_count.copy()
        counts[channel] += 1
        return float(self._error(self.plan_tone_var, self.plan_mix_var, self.primary_var(counts)))
