"""A power limit read from the sweeps: when the tone curves' bend is the interaction's doing.

A panel that limits its power dims the whole frame as its load grows. On the
paper's plan its only mixture is white, but the single-channel sweeps carry
the limit too: a sweep of channel ``c`` at drive ``d`` loads the panel by
``w_c · L_c(d)`` (``w_c`` the channel's share of the white's luminance), so a
bright channel (green) bends near full drive and a dim one (blue) hardly at
all. The tone-curve test then finds "not a power law" on the bright channels,
and the interaction test finds the white short of R + G + B: one cause,
two findings.

:func:`fit_power_limit` fits one model to all three sweeps and the white
references together (in luminance, weighted by the noise model): per channel
a power law of its *undimmed* output, times one load gain shared by every
patch,

``Y = K + δ + g(Σ_c w_c A_c d_c^γ_c / Σ A) · Σ_c A_c d_c^γ_c``,
``g(x) = 1 − a · clip((x − k) / (1 − k), 0, 1)^q``

(``a`` the loss at full load, ``k`` the knee, ``q`` the shape: 1 a linear
loss past a knee, 2 quadratic in load; ``δ`` the black as the sweeps see it
less the measured black, whose own noise would otherwise bend every dark
point). The same ``g`` scales X, Y and Z: a
power limit keeps chromaticity.

The load above weighs each channel by its light (``w_c = A_c / Σ A``). A panel limits the
current it draws, and an OLED's blue subpixels give a tenth of the candela per ampere its green
ones do, so blue can weigh several times its luminance share. The fit therefore also tries the
load with its three weights free (two log-ratios to green; :func:`_free_weights_fit`), and takes
them where they lower χ² far beyond chance (F-test of the two at :data:`FREE_WEIGHTS_P`) and
leave every channel at least :data:`MIN_LOAD_WEIGHT`; ``PowerLimitFit.weights`` is then what the
exported model's load reads. On the independent generator's ``current-load`` probe (paper plan
and its follow-up, seeds 76000–76019, the three power-limit forms) the held-out gain on hidden
colours after the follow-up reached 30 % in 58 of 60 sessions where the luminance law reached
it in 43 (medians 94, 86 and 89 % for the quadratic limit, the knee and the limit past every
channel's load, against 57, 32 and 35 %); on the peer bench's power limits under the probe (45
sessions, three plans) 22 got better by more than 0.005 mean ΔE00 on hidden colours and none
worse. On loads weighed by light nothing changed: the diagnosis suite's 940 sessions, the
follow-up bench's 60 and the peer bench's 1080 channel interactions of seeds 63000–73009.

:func:`tone_bend_explained` says whether this model leaves the sweeps within their noise where
the plain power laws did not, and the white with them: then ``tone-curve-shape`` is reported as
the consequence of ``channel-interaction`` (``consequence_of``), and the
extension can use the load gain as its interaction term
(:class:`~workbench.display.extended.ChannelInteraction` ``load_weights``).

The power limit is *identified* on the sweeps and the white, which every plan
has, but the model exported and cross-validated (:func:`power_limit_model`)
is fitted on every row that carries the load law: the greys and partial-drive
mixtures too, whose loads reach the white's where a sweep's stop at its
channel's share, and in X, Y and Z, each row weighted by its full noise
covariance, the undimmed primaries' XYZ and the black offset free
(:func:`refine_in_XYZ`). Fitted in
luminance on the sweeps and the white alone, the adaptive core's ten levels a
channel traded the knee against the shape, and one reading of each primary at
full drive fixed its chromaticity: on the plans bench's quadratic power limits
and knees the adaptive plan's hidden-colour error was twice the paper plan's.
A knee above every channel's own share leaves the sweeps straight; where the
greys and mixtures show the load gain (:func:`mixtures_show_load_gain`), the
power-limit model is offered to the model choice all the same.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from workbench.diagnostics.detectors import DiagnosisContext, family_size
from workbench.diagnostics.significance import critical_p, f_sf

__all__ = ["PowerLimitFit", "fit_power_limit", "tone_bend_explained", "undimmed_sweeps_tone_test",
           "mixtures_show_load_gain", "refine_in_XYZ", "MIN_LOADED_MIXTURES",
           "power_limit_model",
           "MIN_SWEEP_LEVELS", "MIN_REFIT_SWEEP_LEVELS"]

MIN_SWEEP_LEVELS = 8
"""Sweep levels per channel (below full drive) the joint fit needs to identify a power limit (the
paper's plan has 51, the adaptive plan's core 10)."""

MIN_REFIT_SWEEP_LEVELS = 5
"""Sweep levels per channel a power limit already identified on the whole session needs to be
refitted on a cross-validation fold's training rows (:func:`power_limit_model` with
``min_levels``; :func:`~workbench.diagnostics.model_choice.fit_candidate`). The folds are dealt
out in row order, so where whites interleave a sweep a fold can hold out three of the adaptive
core's ten levels of one channel: at :data:`MIN_SWEEP_LEVELS` that fold could not be fitted and
the identified cause lost the model choice to a flexible model (a knee in the CS-2000's fast
mode, with a white after every eight core patches: 0.145 mean ΔE00 on hidden colours against
0.013). Five levels and the white still fit the model's few parameters (a power law per channel
and one load gain)."""


@dataclass(frozen=True)
class PowerLimitFit:
    """The joint fit: power laws of the undimmed outputs and one load gain (module doc).

    ``chi2`` and ``dof`` are of the sweeps and whites under this model;
    ``chi2_power`` of the same rows under plain power laws (no load gain,
    each sweep normalized by its own full-drive point, the white free). All
    four are of the luminance fit (:func:`fit_power_limit`): a fit refined in
    X, Y and Z (:func:`refine_in_XYZ`, ``full_XYZ`` set) carries those of the
    luminance fit it started from, which the load gain's F-test reads.
    """

    gamma: tuple
    full_Y: tuple  # A_c: undimmed full-drive luminance, black subtracted
    loss: float  # a
    knee: float  # k
    shape: float  # q
    black_offset_Y: float  # the black's luminance as the sweeps see it, less the black rows'
    chi2: float
    dof: int
    chi2_power: float
    dof_power: int
    full_XYZ: tuple | None = None  # undimmed primaries' XYZ (rows: channels), where fitted in XYZ
    black_offset_XYZ: tuple | None = None  # the black as the rows see it less the black rows
    load_weights: tuple | None = None  # what the load weighs each channel by; None: its light

    @property
    def weights(self) -> np.ndarray:
        """Each channel's weight in the load (summing to 1): its share of the undimmed white's
        luminance, or the weights fitted where the rows asked for them (``load_weights``)."""
        if self.load_weights is not None:
            return np.asarray(self.load_weights, dtype=float)
        A = np.asarray(self.full_Y)
        return A / A.sum()

    def gain(self, load) -> np.ndarray:
        x = np.clip((np.asarray(load, dtype=float) - self.knee) / (1.0 - self.knee), 0.0, 1.0)
        return 1.0 - self.loss * x ** self.shape

    def describe(self) -> str:
        form = ("quadratic in load" if abs(self.shape - 2) < 0.25 and self.knee < 0.05 else
                f"past a knee at {100 * self.knee:.0f} % load" if self.knee >= 0.05 else
                f"as load^{self.shape:.1f}")
        text = f"a power limit: {100 * self.loss:.1f} % of the light lost at full load, {form}"
        if self.load_weights is not None:
            A = np.asarray(self.full_Y)
            text += (", its load weighing red, green and blue "
                     + ", ".join(f"{100 * w:.0f} %" for w in self.load_weights)
                     + " (fitted; by their light "
                     + ", ".join(f"{100 * w:.0f} %" for w in A / A.sum()) + ")")
        return text


def _rows(context: DiagnosisContext):
    """(channel, drive, Y black-subtracted, sd) of every sweep point, and the white's (Y, sd)."""
    channel, drive, Y, sd = [], [], [], []
    for sweep in context.sweeps:
        counts = np.ones(sweep.drive.size) if sweep.counts is None else sweep.counts
        values = sweep.XYZ[:, 1]
        channel.append(np.full(sweep.drive.size, sweep.channel))
        drive.append(sweep.drive)
        Y.append(values)
        sd.append(context.noise.sd_Y(values + context.black[1]) / np.sqrt(counts))
    white = float(context.white[1] - context.black[1])
    white_sd = float(context.noise.sd_Y(context.white[1]) / np.sqrt(max(context.white_count, 1)))
    return (np.concatenate(channel), np.concatenate(drive), np.concatenate(Y),
            np.concatenate(sd), white, white_sd)


def _mixtures(context: DiagnosisContext) -> np.ndarray:
    """The fit rows that light two channels or more, white excepted: greys and partial-drive
    mixtures, full field, one row per distinct reading (a mask)."""
    rgb = context.fit.rgb
    return (((rgb > 0).sum(axis=1) >= 2) & ~np.all(rgb >= 255, axis=1) & ~context.copies
            & (context.fit.window_or_full >= 1.0))


def _mixture_rows(context: DiagnosisContext):
    """(drives (M, 3), Y black-subtracted, sd) of :func:`_mixtures`."""
    keep = _mixtures(context)
    Y = context.fit.XYZ[keep, 1]
    return (np.clip(context.fit.rgb[keep] / 255.0, 0, 1), Y - context.black[1],
            context.noise.sd_Y(Y))


def _softmax_weights(ratios) -> np.ndarray:
    """Load weights from the log-ratios of red and blue to green: ``softmax(r_R, 0, r_B)``."""
    e = np.exp(np.array([ratios[0], 0.0, ratios[1]]) - max(ratios[0], 0.0, ratios[1]))
    return e / e.sum()


def _load_law(theta, channel, drive, mix_drive):
    """The luminance model of :func:`fit_power_limit` at ``theta`` (γ × 3, A × 3, a, k, q, δ, and
    with free load weights their log-ratios r_R, r_B to green): ``(sweep points, white,
    mixtures)``, black subtracted (module doc)."""
    gamma, A = theta[:3], theta[3:6]
    a, k, q, offset = theta[6:10]
    total = A.sum()
    weights = A / total if theta.size == 10 else _softmax_weights(theta[10:12])
    L = np.clip(drive, 0, 1) ** gamma[channel]
    load = weights[channel] * L
    x = np.clip((load - k) / (1 - k), 0, 1)
    sweep = A[channel] * L * (1 - a * x ** q) + offset
    powered = np.clip(mix_drive, 0, 1) ** gamma
    summed = (A * powered).sum(axis=1)  # the mixtures undimmed
    x_mix = np.clip((powered @ weights - k) / (1 - k), 0, 1)
    mixed = summed * (1 - a * x_mix ** q) + offset
    return sweep, total * (1 - a) + offset, mixed


def _gain_terms(load, a, k, q):
    """``x^q``, ``1 − a x^q`` and its derivative in the load (0 where ``x`` is clipped) for
    ``x = clip((load − k) / (1 − k), 0, 1)``."""
    raw = (load - k) / (1 - k)
    x = np.clip(raw, 0, 1)
    xq = x ** q
    positive = np.where(x > 0, x, 1.0)
    slope = np.where((raw > 0) & (raw < 1), -a * q * positive ** (q - 1), 0.0) / (1 - k)
    return xq, 1 - a * xq, slope, np.log(positive)


def _load_law_jacobian(theta, channel, drive, mix_drive) -> np.ndarray:
    """∂ :func:`_load_law` / ∂ ``theta`` in closed form: rows the sweep points, the white and
    the mixtures, columns ``theta``'s ten parameters, or twelve with free load weights.

    With finite differences (eleven evaluations a step) :func:`fit_power_limit`'s ten starts were
    85 % of the diagnosis of a session with a channel interaction on the seed authors' plan
    (4.4 s a session; 2.2 s so), and every bench's findings and scores are the same.

    The load is ``Σ_j w_j L_j`` either way. Weighed by light, ``w = A / ΣA`` moves with the
    primaries' luminances (``∂w_j/∂A_i = (δ_ij − w_j) / ΣA``); free, ``w`` is the softmax of the
    last two parameters (``∂w_j/∂r_i = w_j (δ_ij − w_i)``) and the primaries leave it alone."""
    gamma, A = theta[:3], theta[3:6]
    a, k, q = theta[6:9]
    free = theta.size == 12
    total = A.sum()
    weights = _softmax_weights(theta[10:12]) if free else A / total
    # ∂w/∂(the load's own parameters): (parameters, channels), the columns they fill
    if free:
        dweights = np.array([[weights[j] * ((j == i) - weights[i]) for j in range(3)]
                             for i in (0, 2)])
        columns = slice(10, 12)
    else:
        dweights = (np.eye(3) - weights[None, :]) / total
        columns = slice(3, 6)
    n, m = drive.size, mix_drive.shape[0]
    out = np.zeros((n + 1 + m, theta.size))
    rows = np.arange(n)
    # the sweeps: A_c L (1 − a x^q) + δ, L = d^γ_c, load = w_c L
    d = np.clip(drive, 0, 1)
    L = d ** gamma[channel]
    A_c = A[channel]
    load = weights[channel] * L
    xq, gain, slope, log_x = _gain_terms(load, a, k, q)
    dL = L * np.log(np.where(d > 0, d, 1.0))  # ∂L/∂γ_c (0 at d = 0)
    out[rows, channel] = A_c * dL * gain + A_c * L * slope * weights[channel] * dL
    for j in range(3):
        out[rows, 3 + j] = (channel == j) * L * gain
    out[rows, columns] += (A_c * L * slope * L)[:, None] * dweights[:, channel].T
    out[rows, 6] = -A_c * L * xq
    out[rows, 7] = A_c * L * slope * (load - 1) / (1 - k)
    out[rows, 8] = -A_c * L * a * xq * log_x
    out[:n, 9] = 1.0
    # the white: ΣA (1 − a) + δ (its load is 1 whatever the weights)
    out[n, 3:6] = 1 - a
    out[n, 6] = -total
    out[n, 9] = 1.0
    if m:
        dm = np.clip(mix_drive, 0, 1)
        powered = dm ** gamma  # (M, 3)
        outputs = A * powered
        summed = outputs.sum(axis=1)
        load = powered @ weights
        xq, gain, slope, log_x = _gain_terms(load, a, k, q)
        log_d = np.log(np.where(dm > 0, dm, 1.0))
        mix = slice(n + 1, None)
        out[mix, 0:3] = (outputs * log_d * gain[:, None]
                         + (summed * slope)[:, None] * weights * powered * log_d)
        out[mix, 3:6] = powered * gain[:, None]
        out[mix, columns] += (summed * slope)[:, None] * (powered @ dweights.T)
        out[mix, 6] = -summed * xq
        out[mix, 7] = summed * slope * (load - 1) / (1 - k)
        out[mix, 8] = -summed * a * xq * log_x
        out[mix, 9] = 1.0
    return out


def _best_of_starts(residual, jacobian, starts, bounds):
    """The bounded least squares of least cost over ``starts``, or None where none could start."""
    best = None
    for start in starts:
        try:
            fit = least_squares(residual, start, jac=jacobian, bounds=bounds)
        except ValueError:
            continue
        if best is None or fit.cost < best.cost:
            best = fit
    return best


def fit_power_limit(context: DiagnosisContext, min_levels: int = MIN_SWEEP_LEVELS,
                    mixtures: bool = False) -> PowerLimitFit | None:
    """The joint power-law + load-gain fit (module doc), or None without the rows it needs
    (a white, and ``min_levels`` sweep levels below full drive of every channel).

    ``mixtures`` True: the greys and partial-drive mixtures among the fit rows join the fit (their
    load is ``Σ_c w_c A_c d_c^γ_c / Σ A``), and ``chi2``/``chi2_power`` include them. The test
    that identifies a power limit (:func:`tone_bend_explained`) reads the sweeps and the white
    alone, which every plan has; the model that is exported and cross-validated
    (:func:`power_limit_model`) uses the mixtures too, and X, Y and Z (:func:`refine_in_XYZ`).

    Ten starts (five knees, two shapes), each a bounded least squares with its Jacobian in closed
    form (:func:`_load_law_jacobian`)."""
    if context.white_count == 0 or len(context.sweeps) != 3:
        return None
    if any((s.drive < 1).sum() < min_levels for s in context.sweeps):
        return None
    channel, drive, Y, sd, white, white_sd = _rows(context)
    if mixtures:
        mix_drive, mix_Y, mix_sd = _mixture_rows(context)
    else:
        mix_drive, mix_Y, mix_sd = np.zeros((0, 3)), np.zeros(0), np.zeros(0)
    full = np.array([s.full_XYZ[1] for s in context.sweeps])
    if np.any(full <= 0) or white <= 0:
        return None

    def residual(theta, weights=sd):
        sweep, white_pred, mixed = _load_law(theta, channel, drive, mix_drive)
        return np.concatenate([(sweep - Y) / weights, [(white_pred - white) / white_sd],
                               (mixed - mix_Y) / mix_sd])

    scale = 1.0 / np.concatenate([sd, [white_sd], mix_sd])

    def jacobian(theta):
        return _load_law_jacobian(theta, channel, drive, mix_drive) * scale[:, None]

    starts = [[2.2, 2.2, 2.2, *full, 0.05, knee, shape, 0.0]
              for knee in (0.0, 0.2, 0.4, 0.55, 0.7) for shape in (1.0, 2.0)]
    best = _best_of_starts(residual, jacobian, starts,
                           ([0.3] * 3 + [0.0] * 3 + [-0.5, 0.0, 0.5, -np.inf],
                            [8.0] * 3 + [np.inf] * 3 + [0.95, 0.9, 4.0, np.inf]))
    if best is None:
        return None
    free = _free_weights_fit(best, residual, jacobian, Y.size + 1 + mix_Y.size)
    load_weights = None
    if free is not None:
        best, load_weights = free, tuple(float(w) for w in _softmax_weights(free.x[10:12]))
    chi2 = float(2 * best.cost)
    dof = int(Y.size + 1 + mix_Y.size - best.x.size)

    # plain power laws: each sweep normalized by its own full point, the white fitted freely,
    # the mixtures additive
    def residual_power(theta, weights=sd):
        gamma, A, offset = theta[:3], theta[3:6], theta[6]
        mixed = (A * mix_drive ** gamma).sum(axis=1) + offset
        return np.concatenate([
            (A[channel] * np.clip(drive, 0, 1) ** gamma[channel] + offset - Y) / weights,
            (mixed - mix_Y) / mix_sd])

    power = least_squares(residual_power, [2.2, 2.2, 2.2, *full, 0.0],
                          bounds=([0.3] * 3 + [0.0] * 3 + [-np.inf],
                                  [8.0] * 3 + [np.inf] * 3 + [np.inf]))
    chi2_power = float(2 * power.cost)
    return PowerLimitFit(gamma=tuple(float(v) for v in best.x[:3]),
                         full_Y=tuple(float(v) for v in best.x[3:6]),
                         loss=float(best.x[6]), knee=float(best.x[7]), shape=float(best.x[8]),
                         black_offset_Y=float(best.x[9]),
                         chi2=chi2, dof=dof, chi2_power=chi2_power,
                         dof_power=int(Y.size + mix_Y.size - power.x.size),
                         load_weights=load_weights)


FREE_WEIGHTS_P = 1e-6
"""The p-value at which the load's free weights replace its luminance weights
(:func:`_free_weights_fit`): far beyond the family-wise level. The weights change what the model
predicts for colours no row measured, and every cross-validation fold refits them, so a chance
pass swaps one load law for another fold by fold: at the family-wise level, on the paper plan
(sweeps and whites), a knee of the peer bench went from 0.023 to 0.300 mean ΔE00 on hidden
colours and a quadratic limit from 0.015 to 0.079 (their weights' F-test on all the rows p 0.35
and 0.23). A load weighed by current shows at p 1e-16 to 1e-160 on every plan of the
``current-load`` probe."""


MIN_LOAD_WEIGHT = 0.05
"""The least weight a channel may have in a fitted load (:func:`_free_weights_fit`): every
subpixel draws current. Weighed by its light, a blue channel has 6–8 % of the white; by its
current, 15–50 %. A fit that puts a channel near nothing is another interaction read as a
power limit: a drive-following backlight of the diagnosis suite (seed 7702, `paper+greys`)
fitted green at 0.01, and the power-limit model then beat the extension in cross-validation and
handed the choice to the grey ramp (0.241 → 0.260 mean ΔE00 on its validation colours)."""

FREE_WEIGHT_STARTS = ((0.0, 0.0),)
"""Starts of the free load weights' log-ratios (red, blue to green) beside the luminance shares'
own: equal weights. With two more (blue, and red and blue, weighing more than green) a power
limit's diagnosis took 1.0–1.4 s where it takes 0.7–1.1 (0.5–0.9 with the luminance law alone),
and on the ``current-load`` probe's 45 power limits of the peer bench two sessions moved, one
each way (with two starts 0.104 → 0.060 and 0.054 → 0.104 mean ΔE00 on hidden colours)."""


def _free_weights_fit(luminance, residual, jacobian, rows: int):
    """The load gain refitted with the load's channel weights free (two more parameters), where
    that lowers χ² against ``luminance`` (the fit with each channel weighed by its light; F-test
    of the two at :data:`FREE_WEIGHTS_P`) and leaves every channel at :data:`MIN_LOAD_WEIGHT` or
    more; else None.

    The load a panel limits is its current, not its light: an OLED's blue subpixels draw several
    times the current per candela of its green ones, so blue weighs far more in the load than in
    the white's luminance. The luminance-weighted law then puts the knee and the loss where the
    mixtures do not have them."""
    A = luminance.x[3:6]
    shares = np.log(np.maximum(A, 1e-12) / max(A[1], 1e-12))[[0, 2]]
    lower = [0.3] * 3 + [0.0] * 3 + [-0.5, 0.0, 0.5, -np.inf, -6.0, -6.0]
    upper = [8.0] * 3 + [np.inf] * 3 + [0.95, 0.9, 4.0, np.inf, 6.0, 6.0]
    starts = [np.clip(np.concatenate([luminance.x, ratios]), np.array(lower) + 1e-9,
                      np.array(upper) - 1e-9) for ratios in (tuple(shares), *FREE_WEIGHT_STARTS)]
    best = _best_of_starts(residual, jacobian, starts, (lower, upper))
    if best is None:
        return None
    dof = rows - best.x.size
    if dof <= 0 or _softmax_weights(best.x[10:12]).min() < MIN_LOAD_WEIGHT:
        return None
    # the χ² the two weights remove (twice the cost's drop) over their 2 dof, against the
    # residual variance, never below the noise model's
    f_value = (luminance.cost - best.cost) / max(2 * best.cost / dof, 1.0)
    return best if f_sf(max(f_value, 0.0), 2, dof) <= FREE_WEIGHTS_P else None


def _whitened(noise, XYZ_abs, counts):
    """Matrices that whiten each row's XYZ residual: inverse Cholesky factors of its covariance."""
    covariance = noise.covariance(XYZ_abs) / np.asarray(counts, dtype=float)[:, None, None]
    return np.linalg.inv(np.linalg.cholesky(covariance))


def refine_in_XYZ(context: DiagnosisContext, fit: PowerLimitFit, mixtures: bool = True
                  ) -> PowerLimitFit:
    """``fit`` refitted on X, Y and Z of every row it read (sweeps, white, and the greys and
    mixtures where ``mixtures``), each row weighted by its full noise covariance, the undimmed
    primaries' XYZ free: ``XYZ = K + δ + g(load) Σ_c P_c d_c^γ_c``. ``δ``, the black as the
    rows see it less the measured black, is free in X, Y and Z: the black rows' noise is
    subtracted from every row, and a dark sweep point's chromaticity carries it (with ``δ``
    along the white's chromaticity only, the primaries' chromaticities absorbed the rest: on a
    knee of the peer bench, 0.0006 off in x where one reading at full drive is 0.0002 off).
    ``chi2``, ``dof``, ``chi2_power`` and ``dof_power`` stay those of ``fit`` (the luminance
    fit's, read by the load gain's F-test, never by the refinement)."""
    black = context.black
    rows_d, rows_XYZ, rows_n = [], [], []
    for sweep in context.sweeps:
        d = np.zeros((sweep.drive.size, 3))
        d[:, sweep.channel] = np.clip(sweep.drive, 0, 1)
        rows_d.append(d)
        rows_XYZ.append(sweep.XYZ)
        rows_n.append(np.ones(sweep.drive.size) if sweep.counts is None else sweep.counts)
    rows_d.append(np.ones((1, 3)))
    rows_XYZ.append((context.white - black)[None])
    rows_n.append(np.array([max(context.white_count, 1)]))
    if mixtures:
        keep = _mixtures(context)
        rows_d.append(np.clip(context.fit.rgb[keep] / 255.0, 0, 1))
        rows_XYZ.append(context.fit.XYZ[keep] - black)
        rows_n.append(np.ones(keep.sum()))
    drive = np.concatenate(rows_d)
    XYZ = np.concatenate(rows_XYZ)
    whiten = _whitened(context.noise, XYZ + black, np.concatenate(rows_n))
    full = np.array([s.full_XYZ for s in context.sweeps])
    undimmed = full / fit.gain(fit.weights)[:, None]  # each primary at its own full load
    start = np.concatenate([fit.gamma, undimmed.reshape(-1), [fit.loss, fit.knee, fit.shape],
                            fit.black_offset_Y * context.white / context.white[1]])

    def predict(theta):
        gamma, P = theta[:3], theta[3:12].reshape(3, 3)
        a, k, q = theta[12:15]
        if fit.load_weights is None:  # each channel by its light
            load = (P[:, 1] * drive ** gamma).sum(axis=1) / P[:, 1].sum()
        else:
            load = drive ** gamma @ np.asarray(fit.load_weights)
        x = np.clip((load - k) / (1 - k), 0, 1)
        return (drive ** gamma) @ P * (1 - a * x ** q)[:, None] + theta[15:18]

    def residual(theta):
        return np.einsum("nij,nj->ni", whiten, predict(theta) - XYZ).reshape(-1)

    lower = [0.3] * 3 + [-np.inf] * 9 + [-0.5, 0.0, 0.5] + [-np.inf] * 3
    upper = [8.0] * 3 + [np.inf] * 9 + [0.95, 0.9, 4.0] + [np.inf] * 3
    start = np.clip(start, np.array(lower) + 1e-9, np.array(upper) - 1e-9)
    try:
        best = least_squares(residual, start, bounds=(lower, upper))
    except ValueError:
        return fit
    P = best.x[3:12].reshape(3, 3)
    if np.any(P[:, 1] <= 0):
        return fit
    return replace(fit, gamma=tuple(float(v) for v in best.x[:3]),
                   full_Y=tuple(float(v) for v in P[:, 1]), loss=float(best.x[12]),
                   knee=float(best.x[13]), shape=float(best.x[14]),
                   black_offset_Y=float(best.x[16]), full_XYZ=tuple(map(tuple, P.tolist())),
                   black_offset_XYZ=tuple(float(v) for v in best.x[15:18]))


def undimmed_sweeps_tone_test(context: DiagnosisContext, fit: PowerLimitFit,
                              divide: bool = True) -> tuple[float, float]:
    """(p, largest gap) of the tone-curve test on the sweeps with the fitted load gain divided out.

    Each sweep point is divided by ``g`` at its own load (the fitted power
    law's output of the channel times its weight), then tested exactly as
    ``tone-curve-shape`` tests a sweep (power law against the alternative
    shapes and its lack of fit, Bonferroni over the channels); the gap is the
    largest departure from the best power law, in full output. ``divide``
    False: the same test on the sweeps as measured.
    """
    from workbench.diagnostics.detectors import _tone_test_points

    weights = fit.weights
    p_values, gaps = [], []
    for sweep in context.sweeps:
        c = sweep.channel
        L = np.clip(sweep.drive, 0, 1) ** fit.gamma[c]
        gain = fit.gain(weights[c] * L) if divide else np.ones(L.size)
        counts = np.ones(sweep.drive.size) if sweep.counts is None else sweep.counts
        black = context.black[1]
        Y = np.concatenate([np.full(context.black_count, black), sweep.XYZ[:, 1] / gain + black])
        drive = np.concatenate([np.zeros(context.black_count), sweep.drive])
        n = np.concatenate([np.ones(context.black_count), counts])
        sd = context.noise.sd_Y(Y) / np.sqrt(n)
        full = float(sweep.full_XYZ[1] / gain[-1])
        p, gap, *_ = _tone_test_points(drive, Y, sd, black, full, context.noise.dof)
        p_values.append(p)
        gaps.append(gap)
    return min(1.0, len(p_values) * min(p_values)), float(max(gaps))


def _gain_p(fit: PowerLimitFit) -> float:
    """p of the F-test of the load gain's parameters: ``chi2`` against ``chi2_power`` (the
    residual variance never taken below the noise model's, 1 per degree of freedom)."""
    extra = max(fit.dof_power + 1 - fit.dof, 1)
    f_gain = ((fit.chi2_power - fit.chi2) / extra) / max(fit.chi2 / max(fit.dof, 1), 1.0)
    return float(f_sf(max(f_gain, 0.0), extra, max(fit.dof, 1)))


BEND_LEFT_SHARE = 0.25
"""With the load gain divided out, a sweep's largest departure from a power law must fall to
this share of what it was (and below :data:`BEND_LEFT_FLOOR`) where the tone test still finds
one: the test also reads the dark points, whose noise a session's model can underestimate."""

BEND_LEFT_FLOOR = 0.015
"""…of full output."""


def tone_bend_explained(context: DiagnosisContext, fit: PowerLimitFit | None = None
                        ) -> tuple[bool, str, PowerLimitFit | None]:
    """Whether one power limit explains the sweeps' bend and the white together.

    Explained: the load gain lowers the sweeps' and whites' χ² beyond chance
    (F-test of its three parameters against plain power laws, at the
    family-wise level), it is a loss, and with it divided out of the sweeps
    the tone-curve test (:func:`undimmed_sweeps_tone_test`) finds nothing at
    the family-wise level — or what it still finds is a departure of at most
    :data:`BEND_LEFT_SHARE` of the bend and :data:`BEND_LEFT_FLOOR` of full
    output (the dark points' noise, not a shape). Returns (explained, why,
    the fit).
    """
    fit = fit_power_limit(context) if fit is None else fit
    if fit is None:
        return False, "too few sweep levels or no white to fit a power limit on", None
    level = critical_p(family_size(context.apl_testable))
    p_gain = _gain_p(fit)
    p_left, gap_left = undimmed_sweeps_tone_test(context, fit)
    _, gap_measured = undimmed_sweeps_tone_test(context, fit, divide=False)
    flat = gap_left <= min(BEND_LEFT_SHARE * gap_measured, BEND_LEFT_FLOOR)
    explained = bool(p_gain <= level and (p_left > level or flat) and fit.loss > 0)
    why = (f"{fit.describe()} bends the sweeps as measured: with its load gain divided out no "
           f"sweep departs from a power law (tone test p {p_left:.2g}, largest departure "
           f"{100 * gap_left:.2f} % of full output against {100 * gap_measured:.2f} % as "
           f"measured; the gain lowers the sweeps' χ² from {fit.chi2_power:.0f} to "
           f"{fit.chi2:.0f}, p {p_gain:.2g})")
    return explained, why, fit


MIN_LOADED_MIXTURES = 3
"""Greys or mixtures loading the panel beyond its brightest channel alone that
:func:`mixtures_show_load_gain` needs."""


def mixtures_show_load_gain(context: DiagnosisContext) -> tuple[bool, str, PowerLimitFit | None]:
    """Whether one load gain, fitted with the greys and mixtures, explains their shortfall.

    A power limit whose knee lies above every channel's own share of the white's luminance
    leaves the sweeps untouched (:func:`tone_bend_explained` finds no bend to explain); the
    greys and mixtures that load the panel beyond it carry it. Shown: at least
    :data:`MIN_LOADED_MIXTURES` of them load the panel beyond the brightest channel's share,
    the load gain fitted on them, the sweeps and the white (:func:`fit_power_limit` with
    ``mixtures``) lowers χ² against additive power laws beyond chance (F-test of its three
    parameters at the family-wise level), and it is a loss. The model choice is then offered the
    power-limit model, which must lower the cross-validated error to be taken.
    """
    fit = fit_power_limit(context, mixtures=True)
    if fit is None:
        return False, "too few sweep levels or no white to fit a power limit on", None
    drive, _, _ = _mixture_rows(context)
    load = drive ** np.asarray(fit.gamma) @ fit.weights
    loaded = int(np.sum(load > fit.weights.max()))
    if loaded < MIN_LOADED_MIXTURES:
        return False, f"{loaded} greys or mixtures load the panel beyond one channel", fit
    p_gain = _gain_p(fit)
    shown = bool(p_gain <= critical_p(family_size(context.apl_testable)) and fit.loss > 0)
    return shown, (f"{fit.describe()}: with the {loaded} greys and mixtures that load the panel "
                   f"beyond one channel, the load gain lowers χ² from {fit.chi2_power:.0f} to "
                   f"{fit.chi2:.0f}, p {p_gain:.2g}"), fit


def power_limit_model(context: DiagnosisContext, fit: PowerLimitFit | None = None,
                      with_black: bool = True, min_levels: int = MIN_SWEEP_LEVELS):
    """The extended model whose interaction term is the fitted power limit (module doc).

    Power laws of the undimmed outputs, the undimmed primaries' XYZ, the black,
    and one load gain (:class:`~workbench.display.extended.ChannelInteraction`
    with ``load_weights``): it reproduces the dimmed full-drive primaries, the
    sweeps' bend, the greys and the white with one cause. ``fit`` None: fitted
    on the sweeps, the white, the greys and mixtures (:func:`fit_power_limit`
    with ``mixtures``), then in X, Y and Z (:func:`refine_in_XYZ`); a ``fit``
    given is used as it is (its primaries' chromaticities those measured at full
    drive where it was fitted in luminance alone). ``with_black`` False (no
    ``black-offset`` finding): the black is zero, as in the paper's model,
    rather than the black rows' noise. ``min_levels``: the sweep levels per
    channel the fit needs (:data:`MIN_REFIT_SWEEP_LEVELS` to refit an
    identified power limit on a fold).

    Raises
    ------
    InputError
        Where the rows cannot fit a power limit.
    """
    from workbench.diagnostics.evidence import xy_of
    from workbench.display.extended import ChannelInteraction, ExtendedDisplay
    from workbench.display.tone_curves import PowerCurve
    from workbench.errors import InputError

    if fit is None:
        fit = fit_power_limit(context, min_levels, mixtures=True)
        if fit is None:
            raise InputError(f"a power limit needs every channel swept at {min_levels} levels or "
                             "more below full drive, and a white")
        fit = refine_in_XYZ(context, fit)
    full = (np.array(fit.full_XYZ) if fit.full_XYZ is not None
            else np.array([s.full_XYZ for s in context.sweeps]))
    offset = (np.asarray(fit.black_offset_XYZ) if fit.black_offset_XYZ is not None
              else fit.black_offset_Y * context.white / context.white[1])
    black = np.maximum(context.black + offset, 0) if with_black else np.zeros(3)
    return ExtendedDisplay(
        black=black, white=context.white, primaries_xy=xy_of(full),
        primaries_Y=np.asarray(fit.full_Y), tone=tuple(PowerCurve(g) for g in fit.gamma),
        interaction=ChannelInteraction(amount=fit.loss, knee=fit.knee, exponent=fit.shape,
                                       load_weights=tuple(float(w) for w in fit.weights)),
        components=(("black-offset",) if with_black else ()) + ("channel-interaction",))
