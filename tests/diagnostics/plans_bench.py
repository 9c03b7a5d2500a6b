"""Plans bench: paper, paper+greys and adaptive, measured through the CS-2000 protocol, side by side.

Per display and plan, the plan is measured by the workbench's own runner
(:class:`~workbench.measurement.runner.MeasurementRun`, the adaptive plan with
its :class:`~workbench.measurement.adaptive.AdaptivePlanner`) through the real
CS-2000 driver talking to the emulator on a pseudo-terminal, with the
emulator's timing model: the emulator waits a time scale of 0 (so the bench
runs fast), and the session clock is the instrument time that model gives each
patch (:class:`~workbench.measurement.simulation.ModelledSessionClock`), which
is what ``instrument`` reports. The session is then diagnosed
(:func:`workbench.diagnostics.diagnose`) and its exported model
(``diagnosis.extended``) scored in CIEDE2000 on :data:`HIDDEN_COLOURS`
seeded random colours that no plan measured, against the true display,
noiseless, in the state of the session's last two white references (the
state a drift-corrected profile describes; CIELAB white: the diagnosis's
measured white).

Displays:

* the independent generator (:mod:`tests.diagnostics.independent_generator`:
  clean, each form of each effect, the named pairs), its XYZ turned into a
  spectrum the emulator measures (three narrow bands whose weights give the
  display's XYZ exactly; :func:`radiance_of_XYZ`), the emulator's gain noise
  set to the session's drawn noise ``a``. A drift runs on the session
  clock with the time constant of the ``paper`` plan's modelled duration on
  that display in normal speed mode, for every plan and speed mode;
* the simulated headset (``instruments/headset.py``), clean and with a
  10 % channel interaction (its power limit), as ``measure --simulate``
  measures it.

Per session: instrument time (modelled), patches, hidden mean and p95 ΔE00,
the effects named, the validation colours' mean ΔE00 with its 95 % confidence
interval. Acceptance (issue 18) per display: adaptive at most
:data:`TIME_SHARE` of paper's instrument time, its hidden mean ΔE00 at most
paper's + :data:`MEAN_MARGIN`, the injected effects paper names named by
adaptive too; on interaction forms (:data:`INTERACTION_FORMS`) adaptive's
hidden mean ΔE00 at least :data:`INTERACTION_GAIN` below paper's.

The reference's own repeatability: ``--plans … paper-repeat`` (:data:`REPEAT_PLANS`) measures
the ``paper`` plan a second time on the same display, the instrument's noise drawn from another
stream, and the acceptance lines then say how often that repeat misses the first measurement's
hidden mean ΔE00 + :data:`MEAN_MARGIN` (and the first the repeat's), beside adaptive's misses of
each: a per-display margin tighter than the reference's own spread is one no plan can meet on
every display, the reference included.

Run ``PYTHONPATH=. .venv/bin/python -m workbench bench plans --sessions 2``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from tempfile import TemporaryDirectory

import numpy as np

from tests.diagnostics.independent_generator import FORMS, PAIRED_FORMS, generate_session, hidden_colours

__all__ = ["PLANS", "NOISE_STREAM", "REPEAT_PLANS", "KNOWN_PLANS", "HIDDEN_COLOURS", "TIME_SHARE",
           "MEAN_MARGIN", "INTERACTION_FORMS",
           "INTERACTION_GAIN", "FIRST_SEED", "SPEED_MODES", "DRIFT_MET_SIGMA", "scenarios", "radiance_of_XYZ", "PlanOutcome",
           "measure_plan", "run_plans_bench", "summarize", "table", "markdown", "PlansBenchResult",
           "outcomes_from_json"]

PLANS = ("paper", "paper+greys", "adaptive")
NOISE_STREAM = 0x9A1
"""The emulator's noise stream (with the display's seed) for every plan but a repeat."""
REPEAT_PLANS = {"paper-repeat": ("paper", 0x9A2)}
"""Plans measured again: name → (the plan, the emulator's noise stream). The same display and the
same patches as the plan, another draw of the instrument's noise: the reference's repeatability,
which the acceptance lines set beside adaptive's misses. Measured only when asked for
(``--plans``): it costs the paper plan's measurement and diagnosis once more per display."""
KNOWN_PLANS = PLANS + tuple(REPEAT_PLANS)
HIDDEN_COLOURS = 300
TIME_SHARE = 0.35
MEAN_MARGIN = 0.02
INTERACTION_GAIN = 0.30
INTERACTION_FORMS = ("power-limit-quadratic", "knee", "drive-crosstalk")
"""The interaction shapes the paper plan cannot identify (issue 18's acceptance)."""
FIRST_SEED = 40000
SPEED_MODES = {"normal": 0, "fast": 1}
"""The CS-2000's automatic speed modes the bench can run in (``--speed-mode``): normal integrates
up to 242 s in the dark, fast up to 16 s. Fast is another dark end: every patch costs about the
same, so the adaptive plan's fixed core and its validation colours weigh more against the paper
plan's time (its time cap then leaves fewer validation colours). A display's drift keeps the
time scale it has in normal mode: a warm-up is the display's, not the instrument's (run on the
fast paper plan's 21 minutes, a warm-up or a step ran most of its course inside the adaptive
session's seven)."""
DRIFT_MET_SIGMA = 3.0
"""A drift counts as met by a session (:meth:`PlanOutcome.met`) where the display changed during
it by at least this many times its repeatability. The bench runs a drift on the ``paper``
plan's time scale for every plan (a step at 30–70 % of the paper plan's modelled duration, a
decline over all of it), so a session over in a third of that time may end before the step: there
is nothing in its measurements to name, and naming it would be a false finding."""
HEADSET_SCENARIOS = {"headset clean": {}, "headset channel-interaction": {"channel-interaction": 0.1}}

_BANDS_NM = (450.0, 540.0, 620.0)
_BAND_SD_NM = 12.0


def scenarios() -> dict:
    """Scenario name → ("generator", effects) or ("headset", headset effects)."""
    chosen = {"clean": ("generator", {})}
    chosen.update({f"{effect}/{form}": ("generator", {effect: form})
                   for effect, forms in FORMS.items() for form in forms})
    chosen.update({name: ("generator", name) for name in PAIRED_FORMS})
    chosen.update({name: ("headset", effects) for name, effects in HEADSET_SCENARIOS.items()})
    return chosen


def _bands() -> tuple[np.ndarray, np.ndarray]:
    from instruments.headset import WAVELENGTHS_NM, radiance_to_XYZ

    basis = np.exp(-0.5 * ((WAVELENGTHS_NM[:, None] - np.array(_BANDS_NM)[None, :]) / _BAND_SD_NM) ** 2)
    return basis, radiance_to_XYZ(basis.T).T  # (401, 3), (3, 3): XYZ of each band in columns


def radiance_of_XYZ(XYZ) -> np.ndarray:
    """A spectral radiance (401,) whose CIE 1931 XYZ (as the emulator computes it) is ``XYZ``.

    Three narrow Gaussian bands (450, 540 and 620 nm, σ 12 nm); a colour
    outside their triangle gets a small negative weight, which the
    emulator measures like any other radiance.
    """
    basis, columns = _bands()
    return basis @ np.linalg.solve(columns, np.asarray(XYZ, dtype=float))


class _GeneratorDisplay:
    """Shows a patch on a generated display: the patch display and the emulator's radiance source."""

    def __init__(self, generated, clock):
        self.display, self.clock = generated.display, clock
        self.name = generated.session.source.split(",", 1)[-1].strip()
        self.rgb = np.zeros(3)

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        if window < 1.0 or any(surround):
            raise ValueError("the independent generator shows full-field patches only")
        self.rgb = np.asarray(rgb_dac, dtype=float)

    def close(self) -> None:
        pass

    def describe(self) -> str:
        return f"independent generator ({self.name})"

    def XYZ_now(self) -> np.ndarray:
        return self.display.XYZ(self.rgb[None, :], np.array([self.clock.now()]))[0]


def _paper_seconds(display_XYZ, seed: int) -> float:
    """The ``paper`` plan's modelled instrument time on a display (``display_XYZ(rgb)``) in normal
    speed mode: the time scale of the display's drift, whatever the instrument's speed."""
    from instruments.cs2000 import measurement_timing
    from workbench.measurement.plans import measurement_plan

    rgb = np.array([p.rgb for p in measurement_plan("paper", seed).patches], dtype=float)
    return float(sum(measurement_timing(max(Y, 0.0)).duration_s for Y in display_XYZ(rgb)[:, 1]))


@dataclass(frozen=True)
class PlanOutcome:
    """One plan measured on one display."""

    scenario: str
    display: str  # "generator" or "headset"
    seed: int
    plan: str
    effects: dict
    instrument_s: float
    patches: int
    hidden_mean_dE00: float
    hidden_p95_dE00: float
    baseline_hidden_mean_dE00: float
    findings: tuple
    model: str
    validation_n: int
    validation_mean_dE00: float
    validation_ci95: tuple
    decisions: int = 0
    seconds: float = 0.0
    error: str = ""
    drift_change: float | None = None  # the true drift's peak to peak over this session's time
    noise: float | None = None  # the display's repeatability (relative SD of one reading)

    @property
    def named(self) -> set:
        return set(self.findings) - {"unexplained-residual"}

    def met(self, effect: str) -> bool:
        """Whether this session's measurements hold ``effect`` at all: every effect but
        ``temporal-drift``, which only where the display changed during the session by at least
        :data:`DRIFT_MET_SIGMA` times its repeatability (unknown: met)."""
        if effect != "temporal-drift" or self.drift_change is None or self.noise is None:
            return True
        return self.drift_change >= DRIFT_MET_SIGMA * self.noise


def _named_as_paper(pair: dict, met_only: bool = False) -> bool:
    """Whether adaptive names the injected effects paper names (``met_only``: those its own
    session met, :meth:`PlanOutcome.met`)."""
    paper, adaptive = pair["paper"], pair["adaptive"]
    expected = {e for e in set(paper.effects) & paper.named if not met_only or adaptive.met(e)}
    return expected <= adaptive.named


def _ci95(values) -> tuple:
    from scipy import stats

    values = np.asarray(values, dtype=float)
    if values.size < 2:
        return (float("nan"), float("nan"))
    half = stats.t.ppf(0.975, values.size - 1) * values.std(ddof=1) / np.sqrt(values.size)
    return (float(values.mean() - half), float(values.mean() + half))


def measure_plan(plan: str, scenario: str, kind: str, effects, seed: int, out_dir: Path,
                 speed_mode: int = 0):
    """Measure ``plan`` on the scenario's display through the emulator; (session, truth, decisions).

    ``speed_mode`` is set on the instrument before the run (``SPMS``; 0 normal, 1 fast: another
    dark end, :data:`SPEED_MODES`), and the session clock follows it. A drift keeps its time
    scale (the paper plan's duration in normal speed): how fast a display warms up is the
    display's, not the instrument's.

    ``truth(rgb)`` is the display's noiseless XYZ in the state of the session's last two whites.
    Returns ``(session, truth, decisions, end_s, drift_change, repeatability)``: ``drift_change``
    the generated display's drift, peak to peak, over the session's instrument time (None: the
    headset), ``repeatability`` the emulator's relative SD of one reading.
    """
    from instruments.cs2000 import CS2000Emulator, open_cs2000, serve_on_pty
    from instruments.headset import SimulatedHeadset, radiance_to_XYZ
    from instruments.patch_display import SimulatedPatchDisplay
    from workbench.measurement.adaptive import AdaptivePlanner, AdaptiveSettings, adaptive_core_plan
    from workbench.measurement.journal import journal_to_session
    from workbench.measurement.plans import measurement_plan
    from workbench.measurement.runner import MeasurementRun, RunFinished
    from workbench.measurement.simulation import InstrumentTimingModel, ModelledSessionClock

    clock = ModelledSessionClock()
    timing = InstrumentTimingModel(speed_mode=speed_mode)
    if kind == "generator":
        generated = generate_session(effects, seed=seed, plan="paper")
        generator = generated.display
        generator.session_s = _paper_seconds(generator.light, seed)
        shown = _GeneratorDisplay(generated, clock)
        display, repeatability = shown, float(generated.noise)

        def radiance_source():
            radiance = radiance_of_XYZ(shown.XYZ_now())
            clock.advance(timing.measurement_s(radiance))
            return radiance
    else:
        headset = SimulatedHeadset(effects, clock=clock.now)
        headset.session_length_s = _paper_seconds(lambda rgb: radiance_to_XYZ(headset.radiance(rgb)), seed)
        display, repeatability = SimulatedPatchDisplay(headset), 0.001

        def radiance_source():
            radiance = headset.current_radiance()
            clock.advance(timing.measurement_s(radiance))
            return radiance
    planner = None
    plan, stream = REPEAT_PLANS.get(plan, (plan, NOISE_STREAM))
    if plan == "adaptive":
        settings = AdaptiveSettings(seed=seed)
        run_plan, planner = adaptive_core_plan(seed), AdaptivePlanner(settings)
        extra = {"adaptive": settings.to_json()}
    else:
        run_plan, extra = measurement_plan(plan, seed), {}
    emulator = CS2000Emulator(radiance_source, time_scale=0.0, seed=[seed, stream], repeatability=repeatability)
    server = serve_on_pty(emulator)
    try:
        with open_cs2000(server.port, timeout_s=10.0) as meter:
            if speed_mode:
                meter.set_speed_mode(speed_mode)
            run = MeasurementRun.start(out_dir, run_plan, display, meter, settings=extra,
                                       clock=lambda header, journal: clock, planner=planner)
            for event in run.events():
                if isinstance(event, RunFinished) and event.summary.status != "finished":
                    raise RuntimeError(event.summary.one_line())
            journal = run.journal_so_far()
    finally:
        server.close()
    session = journal_to_session(journal)
    whites = np.flatnonzero(session.mask("white"))[-2:]
    t_reference = float(np.mean(session.t_s[whites]))
    if kind == "generator":
        gain = float(np.mean(generator._drift(session.t_s[whites]))) if generator.drift is not None else 1.0

        def truth(rgb):
            return generator.light(np.atleast_2d(rgb)) * gain
    else:
        def truth(rgb):
            return radiance_to_XYZ(headset.radiance(np.atleast_2d(rgb), t_reference))
    end_s = journal.session_end_s()
    change = None
    if kind == "generator":
        change = (float(np.ptp(generator._drift(np.linspace(0.0, end_s, 500))))
                  if generator.drift is not None else 0.0)
    return session, truth, len(journal.decisions), end_s, change, repeatability


def _outcome(plan, scenario, kind, effects, seed, strict=False, speed_mode=0) -> PlanOutcome:
    from workbench.colorimetry import delta_E2000
    from workbench.diagnostics import diagnose

    started = time.perf_counter()
    label = effects if isinstance(effects, dict) else dict(PAIRED_FORMS[effects])
    try:
        with TemporaryDirectory(prefix="plans-bench-") as folder:
            session, truth, decisions, end_s, change, repeatability = measure_plan(
                plan, scenario, kind, effects, seed, Path(folder) / "session", speed_mode)
        diagnosis = diagnose(session)
    except Exception as error:  # a bench reports a failing session and goes on
        if strict:
            raise
        nan = float("nan")
        return PlanOutcome(scenario, kind, seed, plan, label, nan, 0, nan, nan, nan, (), "", 0, nan,
                           (nan, nan), seconds=time.perf_counter() - started,
                           error=f"{type(error).__name__}: {error}")
    rgb = hidden_colours(HIDDEN_COLOURS, seed)
    reference = truth(rgb)
    exported = delta_E2000(diagnosis.extended.forward(rgb), reference, diagnosis.white)
    baseline = delta_E2000(diagnosis.baseline.forward(rgb), reference, diagnosis.white)
    choice = getattr(diagnosis, "model_choice", None)
    return PlanOutcome(
        scenario=scenario, display=kind, seed=seed, plan=plan, effects=label,
        instrument_s=float(end_s), patches=len(session),
        hidden_mean_dE00=float(np.mean(exported)), hidden_p95_dE00=float(np.percentile(exported, 95)),
        baseline_hidden_mean_dE00=float(np.mean(baseline)),
        findings=tuple(f.effect for f in diagnosis.findings),
        model=str(getattr(choice, "chosen", "") or ""),
        validation_n=int(diagnosis.extended_dE.size),
        validation_mean_dE00=float(np.mean(diagnosis.extended_dE)),
        validation_ci95=_ci95(diagnosis.extended_dE), decisions=decisions,
        seconds=time.perf_counter() - started, drift_change=change, noise=repeatability)


def run_plans_bench(sessions: int = 2, names=None, plans=PLANS, first_seed: int = FIRST_SEED,
                    progress=None, strict: bool = False, speed_mode: int = 0) -> list[PlanOutcome]:
    """Every (scenario, seed, plan): ``sessions`` seeds per scenario, one display per seed, the
    instrument in ``speed_mode`` (:data:`SPEED_MODES`)."""
    known = scenarios()
    chosen = known if names is None else {name: known[name] for name in names}
    jobs = [(name, first_seed + k, plan) for name in chosen for k in range(sessions) for plan in plans]
    outcomes = []
    for number, (name, seed, plan) in enumerate(jobs):
        kind, effects = chosen[name]
        outcomes.append(_outcome(plan, name, kind, effects, seed, strict, speed_mode))
        if progress is not None:
            progress(number + 1, len(jobs), outcomes[-1])
    return outcomes


def _pairs(outcomes) -> dict:
    """(scenario, seed) → {plan: outcome} for sessions without errors."""
    pairs: dict = {}
    for o in outcomes:
        if not o.error:
            pairs.setdefault((o.scenario, o.seed), {})[o.plan] = o
    return pairs


def _form(scenario: str) -> str:
    return scenario.rsplit("/", 1)[-1]


def summarize(outcomes) -> list[dict]:
    """One row per (scenario, plan) with the means, then the adaptive plan's acceptance per scenario."""
    pairs = _pairs(outcomes)
    rows = []
    by_scenario: dict = {}
    for (scenario, _), plans in pairs.items():
        by_scenario.setdefault(scenario, []).append(plans)
    for scenario, sessions in by_scenario.items():
        for plan in KNOWN_PLANS:
            chosen = [s[plan] for s in sessions if plan in s]
            if not chosen:
                continue
            row = {"scenario": scenario, "plan": plan, "n": len(chosen),
                   "instrument_min": float(np.mean([o.instrument_s for o in chosen])) / 60,
                   "patches": float(np.mean([o.patches for o in chosen])),
                   "hidden_mean_dE00": float(np.mean([o.hidden_mean_dE00 for o in chosen])),
                   "hidden_p95_dE00": float(np.mean([o.hidden_p95_dE00 for o in chosen])),
                   "named": _named_counts(chosen),
                   "validation_mean_dE00": float(np.mean([o.validation_mean_dE00 for o in chosen])),
                   "validation_ci95_halfwidth": float(np.mean([(o.validation_ci95[1] - o.validation_ci95[0]) / 2
                                                               for o in chosen]))}
            both = [s for s in sessions if plan in s and "paper" in s]
            if plan == "adaptive" and both:
                share = [s["adaptive"].instrument_s / s["paper"].instrument_s for s in both]
                injected = [_named_as_paper(s) for s in both]
                met = [_named_as_paper(s, met_only=True) for s in both]
                row.update(
                    time_share_max=float(np.max(share)), time_share_mean=float(np.mean(share)),
                    within_time=sum(v <= TIME_SHARE + 1e-9 for v in share),
                    within_mean=sum(s["adaptive"].hidden_mean_dE00 <= s["paper"].hidden_mean_dE00
                                    + MEAN_MARGIN for s in both),
                    named_as_paper=sum(injected), named_as_paper_met=sum(met), sessions=len(both),
                    gain_vs_paper=float(np.mean([1 - s["adaptive"].hidden_mean_dE00
                                                 / s["paper"].hidden_mean_dE00 for s in both])))
            rows.append(row)
    return rows


def _named_counts(chosen) -> dict:
    counts: dict = {}
    for o in chosen:
        for effect in o.findings:
            counts[effect] = counts.get(effect, 0) + 1
    return counts


def _acceptance(outcomes) -> list[str]:
    pairs = [p for p in _pairs(outcomes).values() if "paper" in p and "adaptive" in p]
    if not pairs:
        return []
    share = [p["adaptive"].instrument_s / p["paper"].instrument_s for p in pairs]
    mean_ok = [p["adaptive"].hidden_mean_dE00 <= p["paper"].hidden_mean_dE00 + MEAN_MARGIN for p in pairs]
    named_ok = [_named_as_paper(p) for p in pairs]
    met_ok = [_named_as_paper(p, met_only=True) for p in pairs]
    lines = [f"acceptance over {len(pairs)} displays: adaptive ≤ {100 * TIME_SHARE:.0f} % of paper's "
             f"instrument time on {sum(s <= TIME_SHARE + 1e-9 for s in share)} (max "
             f"{100 * max(share):.0f} %, mean {100 * np.mean(share):.0f} %); hidden mean ΔE00 ≤ "
             f"paper + {MEAN_MARGIN} on {sum(mean_ok)}; the injected effects paper names named too "
             f"on {sum(named_ok)}, those the adaptive session met (a drift that changed the "
             f"display by ≥ {DRIFT_MET_SIGMA:g}× its repeatability during it) on {sum(met_ok)}"]
    interaction = [p for p in pairs if _form(p["paper"].scenario) in INTERACTION_FORMS]
    if interaction:
        gains = [1 - p["adaptive"].hidden_mean_dE00 / p["paper"].hidden_mean_dE00 for p in interaction]
        lines.append(f"interaction forms ({', '.join(INTERACTION_FORMS)}): adaptive ≥ "
                     f"{100 * INTERACTION_GAIN:.0f} % below paper's hidden mean ΔE00 on "
                     f"{sum(g >= INTERACTION_GAIN for g in gains)} of {len(gains)} (gain min "
                     f"{100 * min(gains):.0f} %, mean {100 * np.mean(gains):.0f} %)")
    lines += _repeatability(pairs)
    misses = []
    for p, s, m, n, e in zip(pairs, share, mean_ok, named_ok, met_ok):
        if s > TIME_SHARE + 1e-9 or not m or not n:
            a, b = p["adaptive"], p["paper"]
            unmet = ("" if n or not e else
                     f" (its drift changed the display by {100 * a.drift_change:.2f} % during it, "
                     f"repeatability {100 * a.noise:.2f} %: not met)")
            misses.append(f"  miss: {a.scenario} seed {a.seed}: time {100 * s:.0f} %, hidden "
                          f"{a.hidden_mean_dE00:.3f} vs paper {b.hidden_mean_dE00:.3f}, named "
                          f"[{', '.join(a.findings) or 'none'}] vs paper [{', '.join(b.findings) or 'none'}]"
                          + unmet)
    return lines + misses


def _repeatability(pairs) -> list[str]:
    """The paper plan's repeat against its first measurement, beside adaptive against each (the
    displays that have all three)."""
    lines = []
    for repeat in REPEAT_PLANS:
        both = [p for p in pairs if repeat in p]
        if not both:
            continue

        def misses(a, b):
            return sum(p[a].hidden_mean_dE00 > p[b].hidden_mean_dE00 + MEAN_MARGIN for p in both)

        first, again = (np.mean([p[k].hidden_mean_dE00 for p in both]) for k in ("paper", repeat))
        lines.append(
            f"the paper plan's repeatability ({repeat}: the same {len(both)} displays and patches, "
            f"another draw of the instrument's noise): hidden mean ΔE00 {first:.4f} and {again:.4f}; "
            f"the repeat misses the first + {MEAN_MARGIN} on {misses(repeat, 'paper')}, the first "
            f"the repeat's on {misses('paper', repeat)}; adaptive misses the first on "
            f"{misses('adaptive', 'paper')}, the repeat on {misses('adaptive', repeat)}")
    return lines


def table(outcomes) -> str:
    """A text table: per scenario and plan, then the acceptance lines and any failed session."""
    rows = summarize(outcomes)
    width = max([len(r["scenario"]) for r in rows] + [8])
    head = (f"{'scenario':<{width}} {'plan':<11} {'n':>2} {'min':>6} {'patches':>7} {'hidden':>7} "
            f"{'p95':>6} {'valid ±CI':>12} {'time':>5}  named")
    lines = [f"plans bench: instrument minutes from the CS-2000 emulator's timing model; hidden = "
             f"exported model's mean ΔE00 on {HIDDEN_COLOURS} colours no plan measured (true "
             "display, reference state); valid = validation colours' mean ΔE00 ± 95 % CI; "
             "time = adaptive over paper", head, "-" * len(head)]
    for r in rows:
        named = ", ".join(f"{k} {v}/{r['n']}" for k, v in r["named"].items()) or "none"
        share = f"{100 * r['time_share_mean']:.0f}%" if "time_share_mean" in r else ""
        lines.append(f"{r['scenario']:<{width}} {r['plan']:<11} {r['n']:>2} {r['instrument_min']:>6.1f} "
                     f"{r['patches']:>7.0f} {r['hidden_mean_dE00']:>7.3f} {r['hidden_p95_dE00']:>6.3f} "
                     f"{r['validation_mean_dE00']:>6.3f}±{r['validation_ci95_halfwidth']:<5.3f} "
                     f"{share:>5}  {named}")
    lines += _acceptance(outcomes)
    errors = [o for o in outcomes if o.error]
    if errors:
        lines.append(f"sessions that failed (left out): {len(errors)}")
        lines += [f"  {o.scenario} seed {o.seed} {o.plan}: {o.error}" for o in errors]
    return "\n".join(lines)


def markdown(outcomes) -> str:
    """The docs' table: per scenario, paper | paper+greys | adaptive (minutes, hidden mean / p95)."""
    rows = summarize(outcomes)
    by = {(r["scenario"], r["plan"]): r for r in rows}
    scenarios_ = list(dict.fromkeys(r["scenario"] for r in rows))
    lines = ["| display | n | paper: min, mean / p95 ΔE00 | paper+greys | adaptive | adaptive time | "
             "adaptive vs paper (mean ΔE00) | effects named (paper → adaptive) |",
             "|---|---|---|---|---|---|---|---|"]
    for s in scenarios_:
        cells = []
        for plan in PLANS:
            r = by.get((s, plan))
            cells.append("—" if r is None else
                         f"{r['instrument_min']:.1f} min, {r['hidden_mean_dE00']:.3f} / {r['hidden_p95_dE00']:.3f}")
        a, p = by.get((s, "adaptive")), by.get((s, "paper"))
        share = "—" if a is None or "time_share_mean" not in a else f"{100 * a['time_share_mean']:.0f} %"
        delta = ("—" if a is None or p is None else
                 f"{a['hidden_mean_dE00'] - p['hidden_mean_dE00']:+.3f}")

        def named(r):
            return "none" if r is None or not r["named"] else ", ".join(
                f"{k} {v}/{r['n']}" for k, v in r["named"].items())
        n = (a or p)["n"]
        lines.append(f"| {s} | {n} | {' | '.join(cells)} | {share} | {delta} | {named(p)} → {named(a)} |")
    return "\n".join(lines)


@dataclass(frozen=True)
class PlansBenchResult:
    outcomes: list
    as_markdown: bool = False

    def to_json(self) -> dict:
        return {"rows": summarize(self.outcomes), "sessions": [asdict(o) for o in self.outcomes]}

    def summary(self) -> str:
        return markdown(self.outcomes) + "\n\n" + "\n".join(_acceptance(self.outcomes)) \
            if self.as_markdown else table(self.outcomes)


def outcomes_from_json(paths) -> list[PlanOutcome]:
    """Outcomes saved by ``bench plans --json`` (several runs pooled)."""
    outcomes = []
    for path in paths:
        for data in json.loads(Path(path).read_text())["sessions"]:
            data["findings"] = tuple(data["findings"])
            data["validation_ci95"] = tuple(data["validation_ci95"])
            outcomes.append(PlanOutcome(**data))
    return outcomes


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.diagnostics.plans_bench",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--sessions", type=int, default=2)
    parser.add_argument("--scenarios", nargs="+", help=f"of {', '.join(scenarios())}")
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED)
    parser.add_argument("--speed-mode", choices=SPEED_MODES, default="normal",
                        help="the instrument's speed mode (another dark end: fast integrates 16 s at most)")
    parser.add_argument("--plans", nargs="+", choices=KNOWN_PLANS, default=list(PLANS),
                        help="measure only these plans (pool with --load for a table beside the "
                             "others; paper-repeat: the paper plan again, another noise draw)")
    parser.add_argument("--json", metavar="FILE")
    parser.add_argument("--markdown", action="store_true")
    parser.add_argument("--load", nargs="+", metavar="FILE",
                        help="pool the sessions of earlier --json files instead of measuring")
    args = parser.parse_args(argv)
    if args.load:
        print(PlansBenchResult(outcomes_from_json(args.load), args.markdown).summary())
        return 0
    outcomes = run_plans_bench(args.sessions, args.scenarios, plans=tuple(args.plans),
                               first_seed=args.first_seed, speed_mode=SPEED_MODES[args.speed_mode],
                               progress=lambda d, t, o: print(f"\r{d}/{t} {o.scenario} {o.plan}".ljust(60),
                                                              end="", file=sys.stderr, flush=True))
    print(file=sys.stderr)
    result = PlansBenchResult(outcomes, args.markdown)
    if args.json:  # first: a summary of one plan alone has no pairs to compare
        Path(args.json).write_text(json.dumps(result.to_json(), indent=1, default=str))
    print(result.summary())
    return 0


if __name__ == "__main__":
    sys.exit(main())
