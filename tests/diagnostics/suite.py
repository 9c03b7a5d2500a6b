"""The seeded acceptance suite: sessions of the independent generator, diagnosed, and the rates.

:func:`suite_cases` lists the sessions: clean ones, every form of every
effect alone (:data:`SEEDS_PER_FORM` seeds each), and pairs of effects in
random forms; noise drawn from 0.05–0.5 %. :func:`run_suite` diagnoses each
and :class:`SuiteResult` holds the rates the issue's acceptance asks for:

- clean sessions with any finding (goal ≤ 5 %);
- each injected effect named (goal ≥ 95 % of its sessions);
- sessions with a false finding: an effect named that was not injected
  (goal ≤ 5 %); ``unexplained-residual`` is counted apart, since it names no
  cause;
- held-out gain where an effect is present (goal ≥ 30 %), and no loss on
  clean sessions.

Used by ``tests/diagnostics/test_acceptance_suite.py`` and by
``python -m workbench bench diagnose-suite``.
"""

from __future__ import annotations

import itertools
import statistics
import time
from dataclasses import asdict, dataclass

import numpy as np

from tests.diagnostics.independent_generator import FORMS, generate_session

__all__ = ["SEEDS_PER_FORM", "CLEAN_SESSIONS", "suite_cases", "run_suite", "SuiteResult"]

SEEDS_PER_FORM = 3
CLEAN_SESSIONS = 24
PAIRS = 10


def suite_cases(seed: int = 0) -> list[tuple[int, dict]]:
    """(seed, {effect: form}) of every session of the suite."""
    cases = [(1000 * seed + i, {}) for i in range(CLEAN_SESSIONS)]
    n = 0
    for effect, forms in FORMS.items():
        for form in forms:
            for k in range(SEEDS_PER_FORM):
                cases.append((1000 * seed + 100 + n, {effect: form}))
                n += 1
    rng = np.random.default_rng([seed, 5])
    pairs = list(itertools.combinations(FORMS, 2))
    for i, (first, second) in enumerate(pairs[:PAIRS]):
        cases.append((1000 * seed + 500 + i, {first: str(rng.choice(FORMS[first])),
                                              second: str(rng.choice(FORMS[second]))}))
    return cases


@dataclass(frozen=True)
class SuiteResult:
    sessions: int
    clean_sessions: int
    clean_with_finding: int
    effect_sessions: dict
    effect_named: dict
    false_finding_sessions: int
    false_findings: dict
    unexplained_sessions: int
    gains_pct: list
    clean_losses: int
    seconds_per_session: float

    @property
    def clean_rate(self) -> float:
        return self.clean_with_finding / max(self.clean_sessions, 1)

    @property
    def false_rate(self) -> float:
        return self.false_finding_sessions / max(self.sessions, 1)

    def named_rate(self, effect: str) -> float:
        return self.effect_named.get(effect, 0) / max(self.effect_sessions.get(effect, 0), 1)

    @property
    def gain_fraction_30(self) -> float:
        return float(np.mean(np.asarray(self.gains_pct) >= 30)) if self.gains_pct else 0.0

    def to_json(self) -> dict:
        document = asdict(self)
        document.update(clean_rate=self.clean_rate, false_rate=self.false_rate,
                        named_rate={e: self.named_rate(e) for e in self.effect_sessions},
                        gain_median_pct=statistics.median(self.gains_pct) if self.gains_pct else None,
                        gain_fraction_at_least_30pct=self.gain_fraction_30)
        return document

    def summary(self) -> str:
        lines = [f"{self.sessions} sessions of the independent generator "
                 f"({self.seconds_per_session * 1000:.0f} ms each):",
                 f"  clean sessions with any finding: {self.clean_with_finding}/{self.clean_sessions} "
                 f"({100 * self.clean_rate:.1f} %, goal ≤ 5 %)",
                 f"  sessions with a false finding: {self.false_finding_sessions}/{self.sessions} "
                 f"({100 * self.false_rate:.1f} %, goal ≤ 5 %)"
                 + (f": {self.false_findings}" if self.false_findings else ""),
                 f"  unexplained-residual named in {self.unexplained_sessions} session(s)"]
        for effect in self.effect_sessions:
            lines.append(f"  {effect}: named in {self.effect_named.get(effect, 0)}/"
                         f"{self.effect_sessions[effect]} ({100 * self.named_rate(effect):.0f} %, "
                         "goal ≥ 95 %)")
        if self.gains_pct:
            lines.append(f"  held-out gain where an effect is present: median "
                         f"{statistics.median(self.gains_pct):.0f} %, ≥ 30 % in "
                         f"{100 * self.gain_fraction_30:.0f} % of them, lowest "
                         f"{min(self.gains_pct):.0f} %")
        lines.append(f"  clean sessions where the extension loses to the baseline: "
                     f"{self.clean_losses}")
        return "\n".join(lines)


def run_suite(seed: int = 0, cases=None, progress=None) -> SuiteResult:
    """Diagnose every case of :func:`suite_cases` and count."""
    from workbench.diagnostics import diagnose

    cases = suite_cases(seed) if cases is None else cases
    clean = clean_found = false_sessions = unexplained = losses = 0
    effect_sessions: dict = {}
    effect_named: dict = {}
    false_findings: dict = {}
    gains = []
    started = time.perf_counter()
    for number, (case_seed, effects) in enumerate(cases):
        generated = generate_session(effects, seed=case_seed)
        diagnosis = diagnose(generated.session)
        named = {f.effect for f in diagnosis.findings} - {"unexplained-residual"}
        unexplained += any(f.effect == "unexplained-residual" for f in diagnosis.findings)
        false = named - set(effects)
        if false:
            false_sessions += 1
            for effect in false:
                key = f"{effect} (injected: {', '.join(f'{e} {f}' for e, f in effects.items()) or 'none'})"
                false_findings[key] = false_findings.get(key, 0) + 1
        if not effects:
            clean += 1
            clean_found += bool(named)
            losses += diagnosis.extended_score.mean_dE00 > diagnosis.baseline_score.mean_dE00 + 1e-9
        else:
            gains.append(diagnosis.gain_pct)
        for effect in effects:
            effect_sessions[effect] = effect_sessions.get(effect, 0) + 1
            effect_named[effect] = effect_named.get(effect, 0) + (effect in named)
        if progress is not None:
            progress(number + 1, len(cases), generated, diagnosis)
    elapsed = (time.perf_counter() - started) / max(len(cases), 1)
    return SuiteResult(sessions=len(cases), clean_sessions=clean, clean_with_finding=clean_found,
                       effect_sessions=effect_sessions, effect_named=effect_named,
                       false_finding_sessions=false_sessions, false_findings=false_findings,
                       unexplained_sessions=unexplained, gains_pct=[float(g) for g in gains],
                       clean_losses=int(losses), seconds_per_session=elapsed)
