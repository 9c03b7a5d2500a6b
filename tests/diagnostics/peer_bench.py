"""Peer bench: our exported model against the seed authors' method, on colours no plan measured.

Per session of the independent generator
(:mod:`tests.diagnostics.independent_generator`): the session is diagnosed
(:func:`workbench.diagnostics.diagnose`) and its exported model
(``diagnosis.extended``) is kept; the seed authors' grey-ramp linearisation
(:func:`workbench.diagnostics.authors.fit_grey_ramp_linearisation`) is fitted
on the same session (not applicable where the plan has no grey ramp); the
paper's baseline (``diagnosis.baseline``) is kept for reference. All three
are scored in CIEDE2000 (CIELAB white: ``diagnosis.white``, the measured
display white) on :data:`HIDDEN_COLOURS` seeded random colours that no plan
measured, against the true display, noiseless, in the reference state of a
drift correction (the mean of the last two white references: the state a
drift-corrected profile describes, as ``suite.py`` scales its held-out
truth). The authors' method corrects no drift; it is scored against the same
state, which is what a profile is used for.

Per (plan, scenario) the table gives the mean hidden ΔE00 of ours, the
authors' and the baseline, the share of sessions where ours is worse than
the authors' by more than :data:`WORSE_BY` ΔE00, the share where every
injected effect is named, where the first finding is an injected cause, and
where an effect not injected is named (a false finding;
``unexplained-residual`` is counted apart: it names no cause).

The scenarios (:func:`scenarios`): a clean display, each form of
:data:`~tests.diagnostics.independent_generator.NEW_FORMS` alone, and
:data:`~tests.diagnostics.independent_generator.PAIRED_FORMS`; ``--all-forms``
adds every form of the suite. Session ``k`` of every scenario and plan has
seed ``first_seed + k``: one display per seed on every plan, with only its
effects changed between scenarios. ``--probe`` draws every session with a display or a noise
the generator's forms do not
(:data:`~tests.diagnostics.independent_generator.PROBES`: a wide-gamut panel, a
spectroradiometer's chromaticity noise, a slow correlated gain).

Run ``.venv/bin/python -m tests.diagnostics.peer_bench --seeds 3``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from tests.diagnostics.independent_generator import (
    NEW_FORMS,
    PAIRED_FORMS,
    PROBES,
    SUITE_FORMS,
    generate_session,
    hidden_colours,
)

__all__ = ["PLANS", "HIDDEN_COLOURS", "WORSE_BY", "FIRST_SEED", "scenarios", "PeerOutcome",
           "run_peer_bench", "summarize", "table"]

PLANS = ("paper", "paper+greys", "authors-2024")
HIDDEN_COLOURS = 300
WORSE_BY = 0.01
"""ΔE00 by which ours must exceed the authors' mean to count as worse."""
FIRST_SEED = 30000


def scenarios(all_forms: bool = False) -> dict:
    """Scenario name → {effect: form}: clean, the new forms, the named pairs (module doc)."""
    chosen = {"clean": {}}
    if all_forms:
        chosen.update({f"{effect}/{form}": {effect: form}
                       for effect, forms in SUITE_FORMS.items() for form in forms})
    chosen.update({f"{effect}/{form}": {effect: form}
                   for effect, forms in NEW_FORMS.items() for form in forms})
    chosen.update(PAIRED_FORMS)
    return chosen


@dataclass(frozen=True)
class PeerOutcome:
    """One session: what was hidden, what was named, the three hidden-colour scores."""

    plan: str
    scenario: str
    seed: int
    effects: dict
    magnitudes: dict
    noise: float
    findings: tuple  # effect ids in the diagnosis's order, unexplained-residual included
    ours_dE00: float
    baseline_dE00: float
    authors_dE00: float | None  # None: not applicable
    authors_unavailable: str = ""
    model: str = ""
    consequences: tuple = ()  # (effect, its cause) for findings reported as another's consequence
    validation_ours_dE00: float | None = None
    seconds: float = 0.0
    error: str = ""  # the diagnosis failed: why (the session counts in no rate)

    @property
    def named(self) -> set:
        return set(self.findings) - {"unexplained-residual"}

    @property
    def all_named(self) -> bool:
        return set(self.effects) <= self.named

    @property
    def first_is_injected(self) -> bool:
        return bool(self.findings) and self.findings[0] in self.effects

    @property
    def false_named(self) -> set:
        """Named effects not injected, less those reported as an injected cause's consequence
        (a power limit's bend on the sweeps, said to be its consequence, names no false cause)."""
        explained = {effect for effect, cause in self.consequences if cause in self.effects}
        return self.named - set(self.effects) - explained

    @property
    def worse_than_authors(self) -> bool | None:
        if self.authors_dE00 is None:
            return None
        return self.ours_dE00 > self.authors_dE00 + WORSE_BY


def hidden_score(generated, model, white, seed: int) -> float:
    """Mean ΔE00 of ``model`` on the :data:`HIDDEN_COLOURS` hidden colours of ``seed``, against
    the true display of ``generated`` (CIELAB white ``white``)."""
    from workbench.colorimetry import delta_E2000

    rgb = hidden_colours(HIDDEN_COLOURS, seed)
    return float(np.mean(delta_E2000(model.forward(rgb), generated.reference_XYZ(rgb), white)))


def _session_outcome(plan: str, scenario: str, effects: dict, seed: int,
                     strict: bool = False, probe: str | None = None) -> PeerOutcome:
    from workbench.diagnostics import diagnose
    from workbench.diagnostics.authors import fit_grey_ramp_linearisation
    from workbench.errors import InputError

    started = time.perf_counter()
    generated = generate_session(effects, seed=seed, plan=plan, probe=probe)
    try:
        diagnosis = diagnose(generated.session)
    except Exception as error:  # a bench reports a failing session and goes on
        if strict:
            raise
        return PeerOutcome(plan=plan, scenario=scenario, seed=seed, effects=dict(effects),
                           magnitudes={}, noise=generated.noise, findings=(), ours_dE00=np.nan,
                           baseline_dE00=np.nan, authors_dE00=None,
                           error=f"{type(error).__name__}: {error}",
                           seconds=time.perf_counter() - started)
    def score(model) -> float:
        return hidden_score(generated, model, diagnosis.white, seed)

    try:
        authors, unavailable = score(fit_grey_ramp_linearisation(generated.session)), ""
    except InputError as error:
        authors, unavailable = None, str(error)
    choice = getattr(diagnosis, "model_choice", None)
    validation = diagnosis.extended_score
    return PeerOutcome(
        plan=plan, scenario=scenario, seed=seed, effects=dict(effects),
        magnitudes={e: (m if np.ndim(m) == 0 else None) for e, (_, m) in generated.effects.items()},
        noise=generated.noise, findings=tuple(f.effect for f in diagnosis.findings),
        consequences=tuple((f.effect, f.details["consequence_of"]) for f in diagnosis.findings
                           if f.details.get("consequence_of")),
        ours_dE00=score(diagnosis.extended), baseline_dE00=score(diagnosis.baseline),
        authors_dE00=authors, authors_unavailable=unavailable,
        model=str(getattr(choice, "chosen", "") or ""),
        validation_ours_dE00=None if validation is None else validation.mean_dE00,
        seconds=time.perf_counter() - started)


def run_peer_bench(plans=PLANS, forms=None, seeds: int = 3, first_seed: int = FIRST_SEED,
                   progress=None, strict: bool = False,
                   probe: str | None = None) -> list[PeerOutcome]:
    """Every (plan, scenario, seed) session, diagnosed and scored on hidden colours.

    Parameters
    ----------
    plans : sequence of str
        Built-in plan names.
    forms : dict, sequence or None
        Scenario name → {effect: form}; a sequence of names of :func:`scenarios`
        (``"all"`` among them: every form of the suite too) or of
        ``"effect/form"``; None: :func:`scenarios` ().
    seeds : int
        Sessions per (plan, scenario), seeds ``first_seed`` … ``first_seed + seeds − 1``.
    strict : bool
        Raise where a diagnosis fails (else the session is kept with its ``error``, listed by
        :func:`table` and left out of every rate).
    probe : str, optional
        A key of :data:`~tests.diagnostics.independent_generator.PROBES`: every session drawn
        with that display or noise instead of the generator's own.
    """
    if probe is not None and probe not in PROBES:
        raise ValueError(f"no probe {probe!r}; use one of {sorted(PROBES)}")
    if forms is None:
        chosen = scenarios()
    elif isinstance(forms, dict):
        chosen = dict(forms)
    else:
        known = scenarios(all_forms=True)
        chosen = {}
        for name in forms:
            if name == "all":
                chosen.update(known)
            elif name in known:
                chosen[name] = known[name]
            elif "/" in name:
                effect, form = name.split("/", 1)
                chosen[name] = {effect: form}
            else:
                raise ValueError(f"unknown scenario {name!r}; use one of {sorted(known)}")
    jobs = [(plan, name, effects, first_seed + k) for plan in plans
            for name, effects in chosen.items() for k in range(seeds)]
    outcomes = []
    for number, (plan, name, effects, seed) in enumerate(jobs):
        outcomes.append(_session_outcome(plan, name, effects, seed, strict, probe))
        if progress is not None:
            progress(number + 1, len(jobs), outcomes[-1])
    return outcomes


def _mean(values) -> float | None:
    values = [v for v in values if v is not None]
    return float(np.mean(values)) if values else None


def summarize(outcomes) -> list[dict]:
    """One row per (plan, scenario), in the order first met."""
    groups: dict = {}
    for o in outcomes:
        groups.setdefault((o.plan, o.scenario), [])
        if not o.error:
            groups[(o.plan, o.scenario)].append(o)
    rows = []
    for (plan, scenario), chosen in groups.items():
        if not chosen:
            rows.append({"plan": plan, "scenario": scenario, "n": 0, "ours_dE00": None,
                         "authors_dE00": None, "baseline_dE00": None, "authors_n": 0,
                         "ours_worse": None, "all_named": None, "first_injected": None,
                         "false_sessions": None, "false_findings": {}, "unexplained": 0,
                         "models": []})
            continue
        applicable = [o for o in chosen if o.authors_dE00 is not None]
        injected = [o for o in chosen if o.effects]
        false: dict = {}
        for o in chosen:
            for effect in o.false_named:
                false[effect] = false.get(effect, 0) + 1
        rows.append({
            "plan": plan, "scenario": scenario, "n": len(chosen),
            "ours_dE00": _mean(o.ours_dE00 for o in chosen),
            "authors_dE00": _mean(o.authors_dE00 for o in applicable),
            "baseline_dE00": _mean(o.baseline_dE00 for o in chosen),
            "authors_n": len(applicable),
            "ours_worse": (sum(bool(o.worse_than_authors) for o in applicable) / len(applicable)
                           if applicable else None),
            "all_named": (sum(o.all_named for o in injected) / len(injected)) if injected else None,
            "first_injected": (sum(o.first_is_injected for o in injected) / len(injected)
                               if injected else None),
            "false_sessions": sum(bool(o.false_named) for o in chosen) / len(chosen),
            "false_findings": false,
            "unexplained": sum("unexplained-residual" in o.findings for o in chosen),
            "models": sorted({o.model for o in chosen if o.model}),
        })
    return rows


def table(outcomes) -> str:
    """The summary as a text table, then the false findings and the sessions ours loses."""
    rows = summarize(outcomes)

    def num(value, digits=3):
        return "n/a" if value is None else f"{value:.{digits}f}"

    def pct(value):
        return "—" if value is None else f"{100 * value:.0f} %"


    width = max([len(r["scenario"]) for r in rows] + [8])
    header = (f"{'plan':<13} {'scenario':<{width}} {'n':>3}  {'ours':>6} {'authors':>7} "
              f"{'base':>6}  {'worse>' + str(WORSE_BY):>10}  {'named':>6} {'first':>6} "
              f"{'false':>6} {'unexpl':>6}")
    lines = [f"hidden-colour ΔE00 (mean of per-session means over {HIDDEN_COLOURS} colours, "
             "reference state), ours = diagnosis.extended, authors = grey-ramp linearisation, "
             "base = paper's baseline",
             header, "-" * len(header)]
    for r in rows:
        lines.append(
            f"{r['plan']:<13} {r['scenario']:<{width}} {r['n']:>3}  {num(r['ours_dE00']):>6} "
            f"{num(r['authors_dE00']):>7} {num(r['baseline_dE00']):>6}  "
            f"{pct(r['ours_worse']):>10}  {pct(r['all_named']):>6} {pct(r['first_injected']):>6} "
            f"{pct(r['false_sessions']):>6} {r['unexplained']:>6}")
    false = [(r["plan"], r["scenario"], effect, count) for r in rows
             for effect, count in r["false_findings"].items()]
    if false:
        lines.append("false findings:")
        lines += [f"  {plan} {scenario}: {effect} ×{count}" for plan, scenario, effect, count in false]
    errors = [o for o in outcomes if o.error]
    if errors:
        lines.append(f"sessions whose diagnosis failed (left out of the rates): {len(errors)}")
        lines += [f"  {o.plan} {o.scenario} seed {o.seed}: {o.error}" for o in errors[:10]]
    losses = [o for o in outcomes if o.worse_than_authors]
    if losses:
        lines.append(f"sessions where ours is worse than the authors' by more than {WORSE_BY}:")
        lines += [f"  {o.plan} {o.scenario} seed {o.seed}: ours {o.ours_dE00:.3f}, authors "
                  f"{o.authors_dE00:.3f} (findings {', '.join(o.findings) or 'none'}; model "
                  f"{o.model or '?'})" for o in losses]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.diagnostics.peer_bench",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=3, help="sessions per (plan, scenario)")
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED)
    parser.add_argument("--plans", nargs="+", default=list(PLANS))
    parser.add_argument("--forms", nargs="+", default=None,
                        help="scenario names, effect/form, or 'all' (default: clean, the new "
                             "forms and the named pairs)")
    parser.add_argument("--all-forms", action="store_true", help="every form of the suite too")
    parser.add_argument("--json", metavar="FILE", help="write every session's outcome here")
    parser.add_argument("--strict", action="store_true", help="stop at a failing diagnosis")
    parser.add_argument("--probe", choices=sorted(PROBES),
                        help="draw every session with this display or noise instead of the "
                             "generator's own")
    args = parser.parse_args(argv)
    forms = args.forms
    if args.all_forms:
        forms = (forms or []) + ["all"]

    def progress(done, total, outcome):
        print(f"\r{done}/{total} {outcome.plan} {outcome.scenario} seed {outcome.seed} "
              f"({outcome.seconds:.2f} s)".ljust(90), end="", file=sys.stderr, flush=True)

    started = time.perf_counter()
    outcomes = run_peer_bench(plans=args.plans, forms=forms, seeds=args.seeds,
                              first_seed=args.first_seed, progress=progress, strict=args.strict,
                              probe=args.probe)
    print(file=sys.stderr)
    print(table(outcomes))
    print(f"{len(outcomes)} sessions in {time.perf_counter() - started:.0f} s")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump({"rows": summarize(outcomes),
                       "sessions": [{**asdict(o), "findings": list(o.findings)}
                                    for o in outcomes]}, handle, indent=1, default=str)
    return 0


if __name__ == "__main__":
    sys.exit(main())
