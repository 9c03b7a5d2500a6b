"""Follow-up bench: does the proposed follow-up pay for its instrument time on an interaction?

The acceptance criterion measured: *on paper-plan sessions with a power limit,
a knee or a drive crosstalk, the follow-up costs at most 25 % more instrument
time and brings the held-out gain to ≥ 30 % in at least 95 % of sessions.*

Per session of the independent generator
(:mod:`tests.diagnostics.independent_generator`, ``channel-interaction`` in
one form, plan ``paper``):

1. the session is diagnosed (:func:`workbench.diagnostics.diagnose`);
2. :func:`workbench.diagnostics.follow_up.propose_follow_up` proposes a
   follow-up;
3. the follow-up is measured on the same display after the session
   (:meth:`~tests.diagnostics.independent_generator.GeneratedSession.measure_more`:
   the generator's own clock and noise model, a fresh noise stream);
4. the combined session is diagnosed again.

Instrument time. ``share`` is the follow-up's time over the session's on the
generator's own clock (the truth of this bench): the seconds the follow-up's
rows added to the time axis over the session's instrument time, the sum of
its rows' durations (its last row's ``t_s``: the clock starts at 0 and each
row's time is the end of its measurement). ``share_estimated`` is the
proposal's own: ``FollowUp.share`` (its estimated seconds over its estimate of
the session's instrument time, from the session's times per patch).

Held-out gain, before and after the follow-up: ``(baseline − exported) /
baseline`` in mean ΔE00, on the session's validation rows (the diagnosis's
``gain_pct``: the follow-up adds fit rows only, so the validation rows are the
same before and after) and on :data:`HIDDEN_COLOURS` seeded random colours no
plan measured, against the true display, noiseless, in the reference state of
a drift correction (as :mod:`tests.diagnostics.peer_bench` scores them;
CIELAB white: the diagnosis's measured white). Baseline: ``diagnosis.baseline``
(refitted on the combined session after the follow-up), exported:
``diagnosis.extended``; the model chosen is ``diagnosis.model_choice.chosen``.

Run ``PYTHONPATH=. .venv/bin/python -m tests.diagnostics.follow_up_bench --seeds 10``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict, dataclass

import numpy as np

from tests.diagnostics.independent_generator import PROBES, generate_session, hidden_colours

__all__ = ["FORMS", "CRITERION_FORMS", "PLAN", "HIDDEN_COLOURS", "TARGET_GAIN", "TARGET_RATE",
           "FIRST_SEED", "FollowUpOutcome", "session_outcome", "run_follow_up_bench", "summarize",
           "table", "misses"]

CRITERION_FORMS = ("power-limit-quadratic", "knee", "drive-crosstalk")
"""The forms the acceptance criterion names (a power limit, a knee, a drive crosstalk)."""
FORMS = CRITERION_FORMS + ("power-limit", "backlight", "crosstalk")
"""Every ``channel-interaction`` form the bench measures by default."""
PLAN = "paper"
HIDDEN_COLOURS = 300
BUDGET = 0.25
"""The follow-up may cost at most this share of the session's instrument time."""
TARGET_GAIN = 0.30
"""The held-out gain the follow-up should bring the session to."""
TARGET_RATE = 0.95
"""… in at least this share of sessions."""
FIRST_SEED = 30000
FOLLOW_UP_SEED = 1
"""The follow-up's noise stream (``measure_more(patches, seed=FOLLOW_UP_SEED)``)."""


@dataclass(frozen=True)
class FollowUpOutcome:
    """One session, before and after its follow-up (gains are fractions, not %)."""

    form: str
    seed: int
    magnitude: float | None
    noise: float
    session_rows: int
    session_s: float  # the session's instrument time on the generator's clock
    follow_up_rows: int
    follow_up_s: float  # the follow-up's, on the generator's clock
    share: float  # follow_up_s / session_s
    share_estimated: float | None  # FollowUp.share (the proposal's own estimate)
    follow_up_summary: str
    follow_up_notes: tuple
    follow_up_kinds: dict
    combined_rows: int
    findings_before: tuple
    findings_after: tuple
    model_before: str
    model_after: str
    validation_baseline_before: float
    validation_exported_before: float
    validation_baseline_after: float
    validation_exported_after: float
    hidden_baseline_before: float
    hidden_exported_before: float
    hidden_baseline_after: float
    hidden_exported_after: float
    cv_after: dict = None  # model_choice.cv_mean_dE00 after the follow-up (candidate → ΔE00)
    seconds: float = 0.0
    error: str = ""  # a diagnosis or the proposal failed: why (left out of every rate)

    @staticmethod
    def _gain(baseline: float, exported: float) -> float:
        return (baseline - exported) / baseline if baseline > 0 else float("nan")

    @property
    def validation_gain_before(self) -> float:
        return self._gain(self.validation_baseline_before, self.validation_exported_before)

    @property
    def validation_gain_after(self) -> float:
        return self._gain(self.validation_baseline_after, self.validation_exported_after)

    @property
    def hidden_gain_before(self) -> float:
        return self._gain(self.hidden_baseline_before, self.hidden_exported_before)

    @property
    def hidden_gain_after(self) -> float:
        return self._gain(self.hidden_baseline_after, self.hidden_exported_after)

    @property
    def interaction_first_before(self) -> bool:
        return bool(self.findings_before) and self.findings_before[0] == "channel-interaction"

    @property
    def interaction_first_after(self) -> bool:
        return bool(self.findings_after) and self.findings_after[0] == "channel-interaction"

    @property
    def within_budget(self) -> bool:
        return self.share <= BUDGET + 1e-9

    @property
    def meets_gain(self) -> bool:
        """The gain after the follow-up reaches TARGET_GAIN on the validation rows and on the
        hidden colours."""
        return bool(self.validation_gain_after >= TARGET_GAIN and self.hidden_gain_after >= TARGET_GAIN)


def _nan_outcome(form, seed, generated, error, started) -> FollowUpOutcome:
    nan = float("nan")
    return FollowUpOutcome(
        form=form, seed=seed, magnitude=None, noise=generated.noise if generated else nan,
        session_rows=len(generated.session) if generated else 0, session_s=nan, follow_up_rows=0,
        follow_up_s=nan, share=nan, share_estimated=None, follow_up_summary="", follow_up_notes=(),
        follow_up_kinds={}, combined_rows=0, findings_before=(), findings_after=(), model_before="",
        model_after="", validation_baseline_before=nan, validation_exported_before=nan,
        validation_baseline_after=nan, validation_exported_after=nan, hidden_baseline_before=nan,
        hidden_exported_before=nan, hidden_baseline_after=nan, hidden_exported_after=nan,
        seconds=time.perf_counter() - started, error=error)


def session_outcome(form: str, seed: int, strict: bool = False, keep: dict | None = None,
                    probe: str | None = None) -> FollowUpOutcome:
    """Diagnose, propose, measure the follow-up on the same display, diagnose again, score.

    ``keep``: where given, the generated sessions, diagnoses and follow-up are stored in it
    (``generated``, ``diagnosis``, ``follow_up``, ``combined``, ``diagnosis_after``) for a test.
    ``probe``: the generator's probe (``independent_generator.PROBES``) the session is drawn with.
    """
    from workbench.colorimetry import delta_E2000
    from workbench.diagnostics import diagnose
    from workbench.diagnostics.follow_up import propose_follow_up

    started = time.perf_counter()
    generated = None
    try:
        generated = generate_session({"channel-interaction": form}, seed=seed, plan=PLAN,
                                     probe=probe)
        before = diagnose(generated.session)
        follow_up = propose_follow_up(before)
        combined = generated.measure_more(follow_up.patches, seed=FOLLOW_UP_SEED) \
            if follow_up.patches else generated
        after = diagnose(combined.session) if follow_up.patches else before
    except Exception as error:  # a bench reports a failing session and goes on
        if strict:
            raise
        return _nan_outcome(form, seed, generated, f"{type(error).__name__}: {error}", started)
    if keep is not None:
        keep.update(generated=generated, diagnosis=before, follow_up=follow_up, combined=combined,
                    diagnosis_after=after)
    rgb = hidden_colours(HIDDEN_COLOURS, seed)

    def hidden(diagnosis, model, truth) -> float:
        return float(np.mean(delta_E2000(model.forward(rgb), truth, diagnosis.white)))

    truth_before, truth_after = generated.reference_XYZ(rgb), combined.reference_XYZ(rgb)
    session_s = float(np.max(generated.session.t_s))
    follow_up_s = float(np.max(combined.session.t_s)) - session_s
    kinds: dict = {}
    for patch in follow_up.patches:
        kinds[patch.kind] = kinds.get(patch.kind, 0) + 1

    def chosen(diagnosis) -> str:
        return str(getattr(getattr(diagnosis, "model_choice", None), "chosen", "") or "")

    magnitude = generated.effects["channel-interaction"][1]
    return FollowUpOutcome(
        form=form, seed=seed, magnitude=float(magnitude) if np.ndim(magnitude) == 0 else None,
        noise=generated.noise, session_rows=len(generated.session), session_s=session_s,
        follow_up_rows=len(follow_up.patches), follow_up_s=follow_up_s,
        share=follow_up_s / session_s, share_estimated=follow_up.share,
        follow_up_summary=follow_up.summary(), follow_up_notes=tuple(follow_up.notes),
        follow_up_kinds=kinds, combined_rows=len(combined.session),
        findings_before=tuple(f.effect for f in before.findings),
        findings_after=tuple(f.effect for f in after.findings),
        model_before=chosen(before), model_after=chosen(after),
        validation_baseline_before=before.baseline_score.mean_dE00,
        validation_exported_before=before.extended_score.mean_dE00,
        validation_baseline_after=after.baseline_score.mean_dE00,
        validation_exported_after=after.extended_score.mean_dE00,
        hidden_baseline_before=hidden(before, before.baseline, truth_before),
        hidden_exported_before=hidden(before, before.extended, truth_before),
        hidden_baseline_after=hidden(after, after.baseline, truth_after),
        hidden_exported_after=hidden(after, after.extended, truth_after),
        cv_after={k: float(v) for k, v in getattr(getattr(after, "model_choice", None),
                                                   "cv_mean_dE00", {}).items()},
        seconds=time.perf_counter() - started)


def run_follow_up_bench(forms=FORMS, seeds: int = 10, first_seed: int = FIRST_SEED,
                        progress=None, strict: bool = False,
                        probe: str | None = None) -> list[FollowUpOutcome]:
    """Every (form, seed) session: seeds ``first_seed`` … ``first_seed + seeds − 1`` per form
    (one display per seed, only the interaction's form changed between forms)."""
    jobs = [(form, first_seed + k) for form in forms for k in range(seeds)]
    outcomes = []
    for number, (form, seed) in enumerate(jobs):
        outcomes.append(session_outcome(form, seed, strict, probe=probe))
        if progress is not None:
            progress(number + 1, len(jobs), outcomes[-1])
    return outcomes


def _median(values) -> float | None:
    values = [v for v in values if v is not None and np.isfinite(v)]
    return float(np.median(values)) if values else None


def _rate(flags) -> float | None:
    flags = list(flags)
    return sum(map(bool, flags)) / len(flags) if flags else None


def _models(values) -> dict:
    counts: dict = {}
    for value in values:
        counts[value or "?"] = counts.get(value or "?", 0) + 1
    return counts


def _row(name: str, chosen: list) -> dict:
    return {
        "form": name, "n": len(chosen),
        "share_median": _median(o.share for o in chosen),
        "share_max": max((o.share for o in chosen), default=None),
        "share_estimated_median": _median(o.share_estimated for o in chosen),
        "share_estimated_max": max((o.share_estimated for o in chosen if o.share_estimated is not None),
                                   default=None),
        "within_budget": _rate(o.within_budget for o in chosen),
        "validation_hit_before": _rate(o.validation_gain_before >= TARGET_GAIN for o in chosen),
        "validation_hit_after": _rate(o.validation_gain_after >= TARGET_GAIN for o in chosen),
        "hidden_hit_before": _rate(o.hidden_gain_before >= TARGET_GAIN for o in chosen),
        "hidden_hit_after": _rate(o.hidden_gain_after >= TARGET_GAIN for o in chosen),
        "both_hit_after": _rate(o.meets_gain for o in chosen),
        "criterion_met": _rate(o.meets_gain and o.within_budget for o in chosen),
        "validation_gain_before": _median(o.validation_gain_before for o in chosen),
        "validation_gain_after": _median(o.validation_gain_after for o in chosen),
        "hidden_gain_before": _median(o.hidden_gain_before for o in chosen),
        "hidden_gain_after": _median(o.hidden_gain_after for o in chosen),
        "first_before": _rate(o.interaction_first_before for o in chosen),
        "first_after": _rate(o.interaction_first_after for o in chosen),
        "models_before": _models(o.model_before for o in chosen),
        "models_after": _models(o.model_after for o in chosen),
    }


def summarize(outcomes) -> list[dict]:
    """One row per form (in the order first met), then the criterion's forms together, then all."""
    groups: dict = {}
    for o in outcomes:
        groups.setdefault(o.form, [])
        if not o.error:
            groups[o.form].append(o)
    rows = [_row(form, chosen) for form, chosen in groups.items()]
    criterion = [o for form in CRITERION_FORMS for o in groups.get(form, ())]
    if criterion and len(groups) > 1:
        rows.append(_row("criterion forms", criterion))
    if len(groups) > 1:
        rows.append(_row("all", [o for chosen in groups.values() for o in chosen]))
    return rows


def misses(outcomes) -> list[FollowUpOutcome]:
    """Sessions whose follow-up cost more than the budget or left a gain below the target."""
    return [o for o in outcomes if not o.error and not (o.within_budget and o.meets_gain)]


def table(outcomes) -> str:
    """The summary as text tables, then the sessions that miss and those that failed."""
    rows = summarize(outcomes)

    def pct(value, digits=0):
        return "—" if value is None else f"{100 * value:.{digits}f}%"

    width = max([len(r["form"]) for r in rows] + [8])
    head = (f"{'form':<{width}} {'n':>3} | {'share med':>9} {'max':>6} {'est med':>7} {'est max':>7} "
            f"| {'val≥30 b→a':>12} {'hid≥30 b→a':>12} {'both a':>6} {'crit':>5} "
            f"| {'val gain b→a':>13} {'hid gain b→a':>13} | {'1st b→a':>10}")
    lines = [f"follow-up bench: plan {PLAN}, channel-interaction per form; share = follow-up over "
             "session instrument time on the generator's clock (est = FollowUp.share, the "
             "proposal's own estimate); gains = (baseline − exported)/baseline in mean ΔE00 on "
             f"the validation rows (val) and on {HIDDEN_COLOURS} hidden colours (hid), b = "
             f"before, a = after the follow-up; crit = share ≤ {100 * BUDGET:.0f} % and both gains "
             f"≥ {100 * TARGET_GAIN:.0f} %; 1st = channel-interaction named first",
             head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r['form']:<{width}} {r['n']:>3} | {pct(r['share_median'], 1):>9} "
            f"{pct(r['share_max'], 1):>6} {pct(r['share_estimated_median'], 1):>7} "
            f"{pct(r['share_estimated_max'], 1):>7} "
            f"| {pct(r['validation_hit_before']) + '→' + pct(r['validation_hit_after']):>12} "
            f"{pct(r['hidden_hit_before']) + '→' + pct(r['hidden_hit_after']):>12} "
            f"{pct(r['both_hit_after']):>6} {pct(r['criterion_met']):>5} "
            f"| {pct(r['validation_gain_before']) + '→' + pct(r['validation_gain_after']):>13} "
            f"{pct(r['hidden_gain_before']) + '→' + pct(r['hidden_gain_after']):>13} "
            f"| {pct(r['first_before']) + '→' + pct(r['first_after']):>10}")
    lines.append("models exported (before → after):")
    for r in rows:
        def fmt(models):
            return ", ".join(f"{name} ×{count}" for name, count in sorted(models.items()))
        lines.append(f"  {r['form']:<{width}} {fmt(r['models_before'])}  →  {fmt(r['models_after'])}")
    missed = misses(outcomes)
    if missed:
        lines.append(f"sessions over the {100 * BUDGET:.0f} % budget or below a "
                     f"{100 * TARGET_GAIN:.0f} % gain after the follow-up: {len(missed)}")
        for o in missed:
            magnitude = "?" if o.magnitude is None else f"{o.magnitude:.4g}"
            lines.append(
                f"  {o.form} seed {o.seed} (magnitude {magnitude}, "
                f"noise {o.noise:.4f}): share {pct(o.share, 1)} (est {pct(o.share_estimated, 1)}), "
                f"{o.follow_up_rows} patches {o.follow_up_kinds}; val gain "
                f"{pct(o.validation_gain_before)}→{pct(o.validation_gain_after)}, hidden "
                f"{pct(o.hidden_gain_before)}→{pct(o.hidden_gain_after)}; findings "
                f"[{', '.join(o.findings_before) or 'none'}] → [{', '.join(o.findings_after) or 'none'}]; "
                f"model {o.model_before or '?'} → {o.model_after or '?'}")
            lines.append(f"      hidden mean ΔE00 after: baseline {o.hidden_baseline_after:.3f}, exported "
                         f"{o.hidden_exported_after:.3f}; cross-validated fit-row ΔE00 after: "
                         + ", ".join(f"{k} {v:.3f}" for k, v in (o.cv_after or {}).items()))
            if not o.follow_up_rows:
                lines.append(f"      no follow-up: {o.follow_up_summary}")
            for note in o.follow_up_notes:
                lines.append(f"      note: {note}")
    errors = [o for o in outcomes if o.error]
    if errors:
        lines.append(f"sessions that failed (left out of the rates): {len(errors)}")
        lines += [f"  {o.form} seed {o.seed}: {o.error}" for o in errors]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.diagnostics.follow_up_bench",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=10, help="sessions per form")
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED)
    parser.add_argument("--forms", nargs="+", default=list(FORMS))
    parser.add_argument("--json", metavar="FILE", help="write every session's outcome here")
    parser.add_argument("--strict", action="store_true", help="stop at a failing session")
    parser.add_argument("--probe", choices=sorted(PROBES),
                        help="draw every session with this probe of the generator")
    args = parser.parse_args(argv)

    def progress(done, total, outcome):
        print(f"\r{done}/{total} {outcome.form} seed {outcome.seed} ({outcome.seconds:.1f} s)".ljust(70),
              end="", file=sys.stderr, flush=True)

    started = time.perf_counter()
    outcomes = run_follow_up_bench(forms=args.forms, seeds=args.seeds, first_seed=args.first_seed,
                                   progress=progress, strict=args.strict, probe=args.probe)
    print(file=sys.stderr)
    print(table(outcomes))
    print(f"{len(outcomes)} sessions in {time.perf_counter() - started:.0f} s")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump({"rows": summarize(outcomes),
                       "sessions": [{**asdict(o), "validation_gain_before": o.validation_gain_before,
                                     "validation_gain_after": o.validation_gain_after,
                                     "hidden_gain_before": o.hidden_gain_before,
                                     "hidden_gain_after": o.hidden_gain_after}
                                    for o in outcomes]}, handle, indent=1, default=str)
    return 0


if __name__ == "__main__":
    sys.exit(main())
