"""Measure what identifies it: the smallest follow-up measurement for what a diagnosis left open.

:func:`propose_follow_up` reads a diagnosis and proposes the patches that
would identify what it could not, as the evidence asks:

* an ``unexplained-residual`` finding, a ``channel-interaction`` finding
  whose partial-drive shape the fit rows do not identify (shape basis other
  than ``"greys"``: :func:`~workbench.diagnostics.extension.interaction_shape`),
  or a session with no greys or mixtures at partial drive at all while an
  interaction (significant, material or not) or an unexplained residual was
  found → a grey ramp (the levels of
  :data:`~workbench.measurement.plans.GREY_LEVELS` the session lacks) and
  partial-drive mixtures (the 3 × 3 × 3 cube of
  :data:`~workbench.measurement.plans.MIXTURE_LEVELS` without its greys,
  and the two-channel mixtures at those levels with the third channel at 0),
  of kinds ``grey`` and ``mixture`` — fit rows, never ``validation``: the
  held-out colours must stay colours no model saw. A grey ramp the session
  already has (:data:`IDENTIFYING_GREYS` greys above 10 % drive) or mixtures
  it already has (:data:`IDENTIFYING_MIXTURES`) are not proposed again;
* for that ``channel-interaction``, :data:`HIGH_LOAD_MIXTURES` bright mixtures
  (kind ``mixture``) that load the panel beyond its brightest channel alone,
  spread up to the white's load (:func:`_high_load_mixtures`), less those the
  session has: a power limit whose knee lies above every channel's own load
  leaves each sweep a power law and the cube above barely reaches it. Without
  them, on the independent generator's ``power-limit`` form (paper plan, seeds
  76000–76019) the follow-up left the power-limit model unidentified in 18 of
  20 sessions and the extension's interaction term dimmed colours the panel
  does not (hidden colours 0.085 → 0.135 mean ΔE00 on one, the paper's model
  0.085); with them it is exported in 18 and the hidden-colour gain reaches
  30 % in 18 (4 before). Bright patches are quick: on the demo's session the
  eight took 25 s of instrument time, 1.3 % of the session's;
* ``temporal-drift`` untestable for want of repeated whites, or found with
  fewer than :data:`FEW_REFERENCES` distinct references → the follow-up's
  white references come every :data:`DENSE_REFERENCE_INTERVAL` patches
  instead of every :data:`~workbench.measurement.plans.DRIFT_REFERENCE_INTERVAL`.
  Every non-empty follow-up starts and ends on a full-field white (kind
  ``white``): it is measured after the session, and the drift correction and
  the interaction's amounts read the whites, which tie it to the session.
  Whites alone cannot show how a display moved during a session measured
  earlier, so drift on its own proposes nothing (a note says so);
* ``apl-dependence`` untested where the session already shows some patches
  as windows or on surrounds but too few to test → the ``apl`` block
  (:func:`~workbench.measurement.plans.apl_block`, less what was measured)
  with full-field whites every
  :data:`~workbench.measurement.plans.APL_REFERENCE_INTERVAL` patches. A
  session measured full field only proposes nothing for it: whether a display
  limits its power is not guessed;
* nothing unidentified → an empty follow-up ("nothing unidentified: no
  follow-up needed").

Bright patches first: a CS-2000 takes 1–2 s on a bright patch and minutes
near black, so proposed mixtures darker than :data:`DARK_FRACTION` of white
and greys darker than :data:`GREY_DARK_FRACTION` (as the diagnosis's own
model predicts them) are left out, unless they are the only way to reach the
counts that identify the effect.

Instrument time is estimated from the session's own time per patch against
luminance where the session has times (``t_s``), with the runner's
:class:`~workbench.measurement.eta.PatchDurationModel` (gaps longer than a
measurement can take, :data:`MAX_PATCH_S`, are pauses and left out); without
times, from the CS-2000's timing model
(:func:`instruments.cs2000.measurement_timing`, normal mode, 1°) at each
patch's luminance. The follow-up is kept to :data:`BUDGET_SHARE` of the
session's own instrument time where it can be (the dimmest two-channel
mixtures go first, then mixtures down to :data:`IDENTIFYING_MIXTURES`, then
the dimmest greys down to :data:`IDENTIFYING_GREYS`); where even that is
over, it says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from workbench.diagnostics.evidence import partial_greys
from workbench.measurement.eta import PatchDurationModel
from workbench.measurement.plans import (
    APL_REFERENCE_INTERVAL,
    DRIFT_REFERENCE_INTERVAL,
    GREY_LEVELS,
    MIXTURE_LEVELS,
    MeasurementPlan,
    Patch,
    apl_block,
    write_plan_file,
)
from workbench.measurement.runner import format_duration

__all__ = ["FollowUp", "FollowUpReason", "propose_follow_up", "BUDGET_SHARE", "DARK_FRACTION",
           "GREY_DARK_FRACTION",
           "IDENTIFYING_GREYS", "IDENTIFYING_MIXTURES", "FEW_REFERENCES", "DENSE_REFERENCE_INTERVAL",
           "MAX_PATCH_S", "NOTHING_UNIDENTIFIED"]

BUDGET_SHARE = 0.25
"""The follow-up aims at no more than this share of the session's own instrument time."""

DARK_FRACTION = 0.05
"""Proposed mixtures predicted darker than this share of white's luminance are left out."""

GREY_DARK_FRACTION = 0.003
"""Proposed greys darker than this share of white are left out. Lower than for mixtures: the
grey ramp is the tone curve of every candidate model built on it (the seed authors' method
among them), and a ramp that starts at DAC 80 leaves the dark third of every colour to a
straight line from black (independent generator, drive crosstalk on the paper plan: median
held-out gain after the follow-up 8 % with greys from 5 % of white, 54 % from 0.3 %, at 13 %
of the session's instrument time)."""

IDENTIFYING_GREYS = 5
"""Greys above 10 % drive an interaction's shape is fitted on (as
:func:`~workbench.diagnostics.extension.interaction_shape` asks)."""

IDENTIFYING_MIXTURES = 10
"""Partial-drive mixtures among the fit rows that cross-validate it (as ``unexplained-residual`` asks)."""

HIGH_LOAD_LEVELS = (0, 128, 192, 224, 255)
"""Per-channel DAC levels of the bright mixtures a high-load group is chosen from
(:func:`_high_load_mixtures`)."""

HIGH_LOAD_MIXTURES = 8
"""Mixtures the follow-up proposes between the brightest channel's load and the white's."""

FEW_REFERENCES = 6
"""A drift found on fewer distinct white references than this is thinly sampled."""

DENSE_REFERENCE_INTERVAL = 10
"""Patches between the follow-up's whites where drift asks for more references."""

MAX_PATCH_S = 300.0
"""Longest a CS-2000 patch takes (10 s pre-measurement, 242 s measurement, transfer and display):
a longer gap between two rows' times is a pause, not a measurement."""

NOTHING_UNIDENTIFIED = "nothing unidentified: no follow-up needed"
"""The summary of an empty follow-up with nothing left open."""

_WHITE = (255, 255, 255)
_SHAPE_EFFECTS = ("channel-interaction", "unexplained-residual")


@dataclass(frozen=True)
class FollowUpReason:
    """Why a group of the follow-up's patches is there.

    Attributes
    ----------
    group : str
        ``"grey ramp"``, ``"mixtures"``, ``"white references"`` or ``"APL block"``.
    count : int
        Patches of the group in the follow-up.
    serves : tuple of str
        The effects (findings, or untested effects) it identifies.
    why : str
        What it identifies and how it was chosen.
    """

    group: str
    count: int
    serves: tuple
    why: str

    def to_json(self) -> dict:
        return {"group": self.group, "count": self.count, "serves": list(self.serves), "why": self.why}


@dataclass(frozen=True)
class FollowUp:
    """The follow-up measurement a diagnosis proposes (see the module doc).

    Attributes
    ----------
    patches : tuple of Patch
        In the order to measure them; empty when nothing is proposed.
    reasons : tuple of FollowUpReason
        One per group of patches.
    instrument_s : float
        Estimated instrument seconds for the follow-up.
    session_instrument_s : float or None
        The session's own instrument time (measured where it has times).
    timing : str
        How both times were estimated.
    notes : tuple of str
        What is left open that no follow-up here identifies, and budget notes.
    """

    patches: tuple = ()
    reasons: tuple = ()
    instrument_s: float = 0.0
    session_instrument_s: float | None = None
    timing: str = ""
    notes: tuple = field(default_factory=tuple)

    @property
    def patch_count(self) -> int:
        return len(self.patches)

    @property
    def serves(self) -> tuple:
        """Every effect the follow-up serves, in the order its groups name them."""
        return tuple(dict.fromkeys(e for reason in self.reasons for e in reason.serves))

    @property
    def share(self) -> float | None:
        """Instrument time of the follow-up over the session's own (None without a session time)."""
        if not self.session_instrument_s:
            return None
        return self.instrument_s / self.session_instrument_s

    @property
    def within_budget(self) -> bool | None:
        share = self.share
        return None if share is None else bool(share <= BUDGET_SHARE + 1e-9)

    def minutes(self) -> int:
        """The instrument time in whole minutes (at least 1 for a non-empty follow-up)."""
        return max(1, round(self.instrument_s / 60)) if self.patches else 0

    def headline(self) -> str:
        """``"Measure the 60 patches that identify this — about 4 min"`` (the GUI's button text)."""
        if not self.patches:
            return self.summary()
        return f"Measure the {self.patch_count} patches that identify this — about {self.minutes()} min"

    def summary(self) -> str:
        """One line: the headline, what it serves, and its share of the session's instrument time."""
        if not self.patches:
            if self.notes:
                return "no follow-up measurement proposed: " + "; ".join(self.notes)
            return NOTHING_UNIDENTIFIED
        share = self.share
        time = ("" if share is None else
                f"; {100 * share:.0f} % of the session's {format_duration(self.session_instrument_s)} "
                "of instrument time" + ("" if self.within_budget else
                                        f", above the {100 * BUDGET_SHARE:.0f} % aimed at"))
        return f"{self.headline()} ({', '.join(self.serves)}{time})"

    def lines(self) -> tuple:
        """The summary, then one line per group and note (what the CLI prints)."""
        out = [self.summary()]
        out += [f"  {r.count} {r.group} for {', '.join(r.serves)}: {r.why}" for r in self.reasons]
        if self.patches and self.timing:
            out.append(f"  instrument time: {self.timing}")
        if self.patches:
            out += [f"  note: {note}" for note in self.notes]
        return tuple(out)

    def plan(self, name: str = "follow-up") -> MeasurementPlan:
        """The follow-up as a plan (shown exactly as listed)."""
        return MeasurementPlan(name, tuple(self.patches), None)

    def write(self, path):
        """Write the follow-up as a plan file (:func:`~workbench.measurement.plans.write_plan_file`;
        header only when empty); returns the path."""
        return write_plan_file(self.patches, path)

    def to_json(self) -> dict:
        return {
            "summary": self.summary(),
            "patches": self.patch_count,
            "instrument_s": self.instrument_s,
            "session_instrument_s": self.session_instrument_s,
            "share_of_session": self.share,
            "budget_share": BUDGET_SHARE,
            "within_budget": self.within_budget,
            "timing": self.timing,
            "serves": list(self.serves),
            "reasons": [r.to_json() for r in self.reasons],
            "notes": list(self.notes),
            "plan": [[p.kind, *map(int, p.rgb), *((p.window, *map(int, p.surround)) if p.is_apl else ())]
                     for p in self.patches],
        }


# -- what the session already holds ----------------------------------------------------------------


def _partial_mixtures(rgb: np.ndarray) -> np.ndarray:
    """Rows with two or more channels lit, none at full drive, that are not greys."""
    lit = (rgb > 0).sum(axis=1)
    return (lit >= 2) & ~partial_greys(rgb) & np.all(rgb < 255, axis=1)


def _result(diagnosis, effect: str):
    return next((r for r in getattr(diagnosis, "results", ()) if r.effect == effect), None)


def _candidate_mixtures() -> list:
    """The cube of MIXTURE_LEVELS without its greys, then the two-channel mixtures (third channel 0)."""
    cube = [(r, g, b) for r in MIXTURE_LEVELS for g in MIXTURE_LEVELS for b in MIXTURE_LEVELS
            if not r == g == b]
    pairs = []
    for off in (2, 1, 0):  # red+green, red+blue, green+blue
        on = [c for c in range(3) if c != off]
        for u in MIXTURE_LEVELS:
            for v in MIXTURE_LEVELS:
                rgb = [0, 0, 0]
                rgb[on[0]], rgb[on[1]] = u, v
                pairs.append(tuple(rgb))
    return [Patch("mixture", rgb) for rgb in cube] + [Patch("mixture", rgb) for rgb in pairs]


def _loads(context, rgb) -> tuple[np.ndarray, float]:
    """``(load of each row of rgb, the brightest channel's load alone)``: the luminance-weighted
    load of the panel, ``Σ_c w_c L_c(d_c)`` (``w_c`` the channel's share of the summed full-drive
    luminance, ``L_c`` its sweep's output, interpolated), as
    :mod:`~workbench.diagnostics.power_limit` defines it. Read from the sweeps alone, not from a
    model of how the channels interact: that is what the rows are to identify."""
    full = np.array([max(float(s.full_XYZ[1]), 0.0) for s in context.sweeps])
    shares = full / full.sum() if full.sum() > 0 else np.full(3, 1 / 3)
    drive = np.atleast_2d(np.asarray(rgb, dtype=float)) / 255.0
    outputs = np.column_stack([np.interp(drive[:, c], np.concatenate([[0.0], s.drive]),
                                         np.concatenate([[0.0], s.output]))
                               for c, s in enumerate(context.sweeps)])
    return outputs @ shares, float(shares.max())


def _high_load_mixtures(context, present: set) -> tuple[list, float, int]:
    """``(patches, brightest channel's load, rows already there)``: up to
    :data:`HIGH_LOAD_MIXTURES` mixtures of :data:`HIGH_LOAD_LEVELS` (two or three channels lit, not
    grey, not white) that load the panel beyond the brightest channel alone (:func:`_loads`),
    spread evenly over that range of loads up to the white's, less what the session has.

    A loss that sets in only past the brightest channel's own load (a power limit's knee above
    it) leaves every sweep straight: only a mixture brighter than any one channel shows where it
    starts, and the cube of the plans' mixture levels (at most DAC 192) hardly reaches there."""
    raw = context.raw.rgb
    lit = (raw > 0).sum(axis=1)
    existing, top = _loads(context, raw)
    mixtures = (lit >= 2) & ~np.all(raw >= 255, axis=1) & (existing > top)
    already = len({tuple(rgb) for rgb in raw[mixtures].tolist()})
    wanted = HIGH_LOAD_MIXTURES - already
    candidates = [Patch("mixture", (r, g, b)) for r in HIGH_LOAD_LEVELS for g in HIGH_LOAD_LEVELS
                  for b in HIGH_LOAD_LEVELS
                  if sum(v > 0 for v in (r, g, b)) >= 2 and not r == g == b
                  and (r, g, b) not in present]
    if wanted <= 0 or not candidates:
        return [], top, already
    load = _loads(context, [p.rgb for p in candidates])[0]
    inside = [int(i) for i in np.argsort(load, kind="stable") if top < load[i] < 0.99]
    if len(inside) <= wanted:
        return [candidates[i] for i in inside], top, already
    # evenly over the range of loads: the candidate nearest each of ``wanted`` loads
    picks: list = []
    for target in np.linspace(load[inside[0]], load[inside[-1]], wanted):
        picks.append(min((i for i in inside if i not in picks),
                         key=lambda i: abs(load[i] - target)))
    return [candidates[i] for i in sorted(picks, key=lambda i: -load[i])], top, already


# -- luminance and time ------------------------------------------------------------------------------


def _relative_luminance(diagnosis, patches) -> np.ndarray:
    """Each patch's luminance over white's, as the diagnosis's own model predicts it."""
    if not patches:
        return np.zeros(0)
    rgb = np.array([p.rgb for p in patches], dtype=float)
    model = getattr(diagnosis, "extended", None)
    white = getattr(diagnosis, "white", None)
    if model is not None and white is not None and white[1] > 0:
        try:
            Y = np.asarray(model.forward(rgb), dtype=float)[:, 1]
            if np.all(np.isfinite(Y)):
                return Y / float(white[1])
        except Exception:  # noqa: BLE001 - any model that cannot say ranks by the prior below
            pass
    ranking = PatchDurationModel()
    return np.array([ranking.expected_relative_luminance(p) for p in patches])


class _PredictedDurations(PatchDurationModel):
    """The runner's duration model, placing each patch by the luminance the diagnosis's model
    predicts for it rather than by the runner's rough ranking (a power 2.2 of the drive)."""

    def __init__(self, diagnosis):
        super().__init__()
        self._diagnosis = diagnosis
        self._predicted: dict = {}

    def expected_relative_luminance(self, patch: Patch) -> float:
        key = tuple(patch.rgb)
        if key not in self._predicted:
            self._predicted[key] = float(_relative_luminance(self._diagnosis, [patch])[0])
        return self._predicted[key]


class _Timing:
    """Instrument seconds for patches: the session's own times per patch against luminance where it
    has them (:class:`PatchDurationModel`), else the CS-2000's timing model."""

    def __init__(self, diagnosis):
        session = diagnosis.session
        self.diagnosis = diagnosis
        self.white_Y = float(np.max(session.XYZ[:, 1])) if len(session) else 0.0
        white = session.mask("white") | np.all(session.rgb >= 255, axis=1)
        if white.any():
            self.white_Y = float(np.mean(session.XYZ[white, 1]))
        times = session.t_s
        timed = (times is not None and len(times) > 1 and np.ptp(times) > 0
                 and session.metadata.get("time_basis", "time") == "time")
        self.model = None
        patches = [Patch(str(k), tuple(int(round(v)) for v in rgb)) for k, rgb in zip(session.kind, session.rgb)]
        if timed:
            order = np.argsort(times, kind="stable")
            durations = np.diff(times[order])
            model = _PredictedDurations(diagnosis)
            measured, untimed = 0.0, []
            for position, row in enumerate(order):
                duration = durations[position] if position < durations.size else None
                if duration is None or not 0 < duration <= MAX_PATCH_S:
                    untimed.append(patches[row])
                    continue
                model.observe(patches[row], float(session.XYZ[row, 1]), float(duration))
                measured += float(duration)
            if model.remaining_s([]) is not None:
                self.model = model
                self.session_s = measured + (model.remaining_s(untimed) or 0.0)
                self.basis = (f"from the session's own time per patch against luminance ({len(order) - len(untimed)} "
                              "patches timed; the runner's PatchDurationModel, each follow-up patch "
                              "placed at the luminance the diagnosis's model predicts)")
        if self.model is None:
            self.session_s = float(sum(self._cs2000_s(Y) for Y in session.XYZ[:, 1]))
            self.basis = ("from the CS-2000's timing model (normal mode, 1°) at each patch's luminance "
                          "(measured for the session's rows, as the diagnosis's model predicts it for the "
                          "follow-up's): the session has no times of its own")

    @staticmethod
    def _cs2000_s(luminance: float) -> float:
        from instruments.cs2000 import measurement_timing

        return measurement_timing(max(float(luminance), 0.0)).duration_s

    def seconds(self, patches) -> float:
        patches = list(patches)
        if not patches:
            return 0.0
        if self.model is not None:
            return float(self.model.remaining_s(patches))
        relative = _relative_luminance(self.diagnosis, patches)
        return float(sum(self._cs2000_s(r * self.white_Y) for r in relative))


# -- the proposal --------------------------------------------------------------------------------------


def _with_whites(patches: list, interval: int) -> list:
    """A white first, after every ``interval`` patches, and last."""
    if not patches:
        return []
    out = [Patch("white", _WHITE)]
    for i, patch in enumerate(patches, start=1):
        out.append(patch)
        if i % interval == 0 and i < len(patches):
            out.append(Patch("white", _WHITE))
    out.append(Patch("white", _WHITE))
    return out


def _bright_enough(diagnosis, candidates: list, needed: int, floor: float = DARK_FRACTION
                   ) -> tuple[list, list, bool]:
    """(kept, dropped dark, dark kept?): candidates at or above ``floor`` of white, brightest
    first; where fewer than ``needed`` are, the brightest dark ones are kept to reach it."""
    if not candidates:
        return [], [], False
    relative = _relative_luminance(diagnosis, candidates)
    order = np.argsort(-relative, kind="stable")
    bright = [candidates[i] for i in order if relative[i] >= floor]
    dark = [candidates[i] for i in order if relative[i] < floor]
    short = max(0, needed - len(bright))
    return bright + dark[:short], dark[short:], short > 0


def _densest_grey(greys: list) -> int:
    """Index of the inner grey (sorted by level) whose neighbours are closest: dropping it keeps the
    ramp's span and its levels as evenly spread as they can be (ties: the dimmest)."""
    levels = [p.rgb[0] for p in greys]
    gaps = [levels[i + 1] - levels[i - 1] for i in range(1, len(levels) - 1)]
    return 1 + int(np.argmin(gaps))


def _levels(patches) -> str:
    values = sorted({p.rgb[0] for p in patches})
    return ", ".join(map(str, values))


def propose_follow_up(diagnosis) -> FollowUp:
    """The smallest follow-up measurement that identifies what ``diagnosis`` left unidentified.

    Parameters
    ----------
    diagnosis : Diagnosis or LoadOnlyDiagnosis
        As :func:`~workbench.diagnostics.diagnose_what_it_can` returns it.

    Returns
    -------
    FollowUp
        Empty (its summary says why) when nothing a measurement could
        identify is left open.
    """
    session = diagnosis.session
    timing = _Timing(diagnosis)
    notes: list = []
    groups: list = []  # [group, serves, why(kept patches) -> str, patches, role]

    # -- the interaction's shape and the unexplained residual: greys and mixtures -----------------
    context = getattr(diagnosis, "context", None)
    serves: list = []
    whys: list = []
    if context is not None:
        from workbench.diagnostics.extension import interaction_shape

        raw = context.raw
        interaction = _result(diagnosis, "channel-interaction")
        basis = interaction_shape(context)[1]
        has_partial = bool((partial_greys(raw.rgb) | _partial_mixtures(raw.rgb)).any())
        if interaction is not None and interaction.found and basis != "greys":
            serves.append("channel-interaction")
            whys.append("the white fixes the interaction's amounts, not its shape at partial drive "
                        + ("(the shape of subpixel crosstalk is assumed from how the white departs "
                           "channel by channel)" if basis == "channel-specific" else
                           "(the most conservative shape is used until it is identified)"))
        if diagnosis.unexplained is not None:
            serves.append("unexplained-residual")
            whys.append("the held-out error is far above the noise and no named effect accounts "
                        "for it; rows between the sweeps and white show where the model departs")
        if not has_partial and interaction is not None and interaction.significant and not serves:
            serves.append("channel-interaction")
            whys.append("the channels do not add up at white (significant, below the materiality "
                        "floor at the shape assumed) and the session has no grey or mixture at "
                        "partial drive to show what that does below full drive")
        if serves:
            greys_present = partial_greys(raw.rgb) & (raw.rgb[:, 0] / 255.0 > 0.1)
            present = {tuple(int(v) for v in rgb) for rgb in raw.rgb}
            n_bright_greys = len({int(v) for v in raw.rgb[greys_present, 0]})
            n_mixtures = int(_partial_mixtures(raw.rgb).sum())
            common = "; ".join(whys)
            if n_bright_greys < IDENTIFYING_GREYS:
                candidates = [Patch("grey", (v, v, v)) for v in GREY_LEVELS if (v, v, v) not in present]
                greys, dropped, dark_kept = _bright_enough(diagnosis, candidates,
                                                           IDENTIFYING_GREYS - n_bright_greys,
                                                           GREY_DARK_FRACTION)
                greys.sort(key=lambda p: p.rgb[0])

                def grey_why(kept, dropped=dropped, dark_kept=dark_kept, common=common,
                             n_bright_greys=n_bright_greys, candidates=candidates):
                    left_out = [p for p in candidates if p not in kept]
                    why = (f"{common}. A grey ramp (DAC {_levels(kept)}) fits the interaction's shape "
                           f"along the grey axis (the diagnosis needs {IDENTIFYING_GREYS} greys above "
                           f"10 % drive; the session has {n_bright_greys})")
                    if dropped:
                        why += (f"; {len(dropped)} darker than {100 * GREY_DARK_FRACTION:.1f} % of white left "
                                f"out (DAC {_levels(dropped)}: slow on a CS-2000, and the channels barely "
                                "interact there)")
                    if len(left_out) > len(dropped):
                        why += f"; {len(left_out) - len(dropped)} more left out for time (see the notes)"
                    if dark_kept:
                        why += "; some darker ones kept, being the only way to reach that count"
                    return why

                groups.append(["grey ramp", tuple(serves), grey_why, greys, "greys"])
            else:
                notes.append(f"the session already holds {n_bright_greys} greys above 10 % drive: no grey "
                             "ramp proposed")
            if n_mixtures < IDENTIFYING_MIXTURES:
                candidates = [p for p in _candidate_mixtures() if p.rgb not in present]
                mixtures, dropped, dark_kept = _bright_enough(diagnosis, candidates,
                                                              IDENTIFYING_MIXTURES - n_mixtures)

                def mixture_why(kept, dropped=dropped, dark_kept=dark_kept, candidates=candidates):
                    three = sum(1 for p in kept if min(p.rgb) > 0)
                    left_out = len(candidates) - len(kept)
                    why = (f"mixtures at partial drive (DAC levels "
                           f"{', '.join(map(str, MIXTURE_LEVELS))}: {three} three-channel, "
                           f"{len(kept) - three} two-channel) show how the channels combine off the "
                           "grey axis and cross-validate the shape the greys fit, as fit rows (never "
                           "validation rows: the held-out colours stay unseen)")
                    if dropped:
                        why += f"; {len(dropped)} darker than {100 * DARK_FRACTION:.0f} % of white left out"
                    if left_out > len(dropped):
                        why += f"; {left_out - len(dropped)} more, the dimmest, left out for time (see the notes)"
                    if dark_kept:
                        why += "; some darker ones kept, being the only way to reach the count that identifies it"
                    return why

                groups.append(["mixtures", tuple(serves), mixture_why, mixtures, "mixtures"])
            else:
                notes.append(f"the session already holds {n_mixtures} partial-drive mixtures: none proposed")
            if "channel-interaction" in serves:
                proposed = present | {p.rgb for g in groups for p in g[3]}
                loaded, top, already = _high_load_mixtures(context, proposed)
                if loaded:
                    def loaded_why(kept, top=top, already=already):
                        return (f"bright mixtures (DAC levels {', '.join(map(str, HIGH_LOAD_LEVELS[1:]))}) "
                                f"that load the panel beyond its brightest channel alone "
                                f"({100 * top:.0f} % of the channels' summed luminance) and up to the white "
                                f"({already} such rows in the session): a loss that starts only past "
                                "one channel's own load leaves every sweep straight, and only these "
                                "show where it starts and how it grows")
                    groups.append(["high-load mixtures", ("channel-interaction",), loaded_why,
                                   loaded, "loaded"])
            if not any(g[3] for g in groups):
                notes[:] = [("the session already holds the greys and mixtures that would identify "
                             f"{' and '.join(serves)}; repeat the session to tell an unstable display "
                             "from a model gap")]

    # -- apl-dependence: only where the session shows some windows or surrounds already -----------
    apl = _result(diagnosis, "apl-dependence") if context is not None else getattr(diagnosis, "result", None)
    if apl is not None and not apl.testable and session.has_surround_data:
        measured = {(tuple(int(v) for v in rgb), float(w), tuple(int(v) for v in s))
                    for rgb, w, s in zip(session.rgb, session.window_or_full, session.surround_or_black)}
        block = [p for p in apl_block(0)
                 if (p.rgb, float(p.window), tuple(p.surround) if p.is_apl or any(p.surround) else (0, 0, 0))
                 not in measured]
        if block:
            why = ("the session shows some patches as windows or on surrounds, too few to test "
                   f"apl-dependence ({apl.evidence.removeprefix('not testable: ')}); the apl plan's "
                   "windows on black and small windows on grey surrounds, less what was measured, "
                   "test it, with full-field whites between as the apl plan has")
            groups.append(["APL block", ("apl-dependence",), lambda kept, why=why: why, block, "apl"])

    # -- temporal drift: more references where it asked for them ------------------------------------
    drift = _result(diagnosis, "temporal-drift") if context is not None else None
    interval, drift_why, drift_head = DRIFT_REFERENCE_INTERVAL, "", ""
    if drift is not None:
        references = 0 if context.drift is None else int(context.drift.times.size)
        if not drift.testable and session.t_s is not None:
            interval = DENSE_REFERENCE_INTERVAL
            drift_head = f"temporal-drift could not be tested ({drift.evidence.removeprefix('not testable: ')})"
            drift_why = f"{drift_head}: a white every {interval} patches gives the follow-up references of its own"
        elif not drift.testable:
            notes.append("temporal-drift stays untested: the session's rows are not in measurement "
                         "order, and whites measured after it cannot show how the display moved "
                         "during it; measure a session with drift references (every built-in plan has them)")
        elif drift.found and references < FEW_REFERENCES:
            interval = DENSE_REFERENCE_INTERVAL
            drift_head = f"temporal-drift was found on only {references} distinct white references"
            drift_why = f"{drift_head}: a white every {interval} patches samples it more densely"
    if any(g[4] == "apl" for g in groups):
        interval = min(interval, APL_REFERENCE_INTERVAL)

    if not any(g[3] for g in groups):
        if drift_why:
            notes.append(drift_head + ", but whites measured after the session cannot "
                         "show how the display moved during it; measure a session with drift references "
                         "(every built-in plan has them)")
        return FollowUp((), (), 0.0, timing.session_s, timing.basis, tuple(notes))

    # -- the budget: at most BUDGET_SHARE of the session's instrument time, where it can be --------
    def assemble():
        body = [p for g in groups for p in g[3]]
        return _with_whites(body, interval)

    budget = BUDGET_SHARE * timing.session_s if timing.session_s else math.inf
    greys = next((g for g in groups if g[4] == "greys"), None)
    mixtures = next((g for g in groups if g[4] == "mixtures"), None)
    trimmed = 0
    while timing.seconds(assemble()) > budget:
        if mixtures is not None and any(min(p.rgb) == 0 for p in mixtures[3]) \
                and len(mixtures[3]) > IDENTIFYING_MIXTURES:
            two = [p for p in mixtures[3] if min(p.rgb) == 0]
            mixtures[3].remove(two[-1])  # the dimmest two-channel mixture
        elif mixtures is not None and len(mixtures[3]) > IDENTIFYING_MIXTURES:
            mixtures[3].pop()  # the dimmest mixture
        elif greys is not None and len(greys[3]) > max(IDENTIFYING_GREYS, 2):
            greys[3].pop(_densest_grey(greys[3]))
        else:
            break
        trimmed += 1
    patches = assemble()
    seconds = timing.seconds(patches)
    if trimmed:
        notes.append(f"{trimmed} proposed patches left out (the dimmest mixtures first, then greys where "
                     f"they crowd) to keep within {100 * BUDGET_SHARE:.0f} % of the session's instrument time")
    if seconds > budget:
        notes.append(f"it takes {100 * seconds / timing.session_s:.0f} % of the session's instrument time, "
                     f"above the {100 * BUDGET_SHARE:.0f} % aimed at: these are the fewest patches that "
                     "identify it")

    whites = sum(1 for p in patches if p.kind == "white")
    white_serves = tuple(dict.fromkeys([*(("temporal-drift",) if drift_why else ()),
                                        *(e for g in groups for e in g[1])]))
    white_why = ("full-field whites first, last and every "
                 f"{interval} patches: the follow-up is measured after the session, and the drift "
                 "correction (and an interaction's amounts) read the whites, which tie its rows to "
                 "the session's")
    if drift_why:
        white_why = f"{drift_why}; and {white_why}"
    reasons = [FollowUpReason(g[0], len(g[3]), g[1], g[2](g[3])) for g in groups if g[3]]
    reasons.append(FollowUpReason("white references", whites, white_serves, white_why))
    return FollowUp(tuple(patches), tuple(reasons), seconds, timing.session_s, timing.basis, tuple(notes))
