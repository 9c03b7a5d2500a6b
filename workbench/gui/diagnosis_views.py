"""What the Fit & diagnose page plots, taken from a :class:`~workbench.diagnostics.Diagnosis` (no Qt).

The page draws arrays; this module gets them from the diagnosis and the
models it fitted (the models' own ``forward`` and tone curves, the
diagnosis's ΔE00 arrays and ``to_json()``), the same quantities the HTML
report (:mod:`workbench.diagnostics.report`) plots. Nothing here fits or
scores anything. Units: DAC 0–255; normalized output (1 = full drive);
residuals in % of full drive; session time in minutes; ΔE00 CIEDE2000 in the
CIELAB of the measured display white.

Findings are shown generically: :func:`finding_cards` turns every field a
finding has in ``to_json()`` (and every entry elsewhere in it that names the
same effect) into a card, so fields the diagnosis gains later appear without
a change here. :data:`FINDING_PLOTS` maps an effect to the plot of its evidence.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import colour
import numpy as np

from workbench.diagnostics.evidence import channel_sweeps, white_reference_axes, xy_of
from workbench.diagnostics.model_choice import PRIMARIES_AS_MEASURED
from workbench.diagnostics.report import split_consequence

__all__ = [
    "CHANNEL_NAMES",
    "Series",
    "PlotView",
    "SweepView",
    "ValidationRow",
    "FindingCard",
    "ModelChoiceRow",
    "XYZ_to_srgb8",
    "sweep_views",
    "additivity_view",
    "grey_additivity_view",
    "chromaticity_view",
    "white_reference_view",
    "validation_rows",
    "histogram_view",
    "finding_cards",
    "split_consequence",
    "model_choice_rows",
    "model_choice_reason",
    "summary_lines",
    "detail_lines",
    "CheckedRow",
    "checked_rows",
    "CHECKED_KEYS",
    "VERDICT_KEYS",
    "SHOWN_APART",
    "FINDING_PLOTS",
]

CHANNEL_NAMES = ("red", "green", "blue")
_GRID = np.linspace(0.0, 1.0, 256)


@dataclass(frozen=True)
class Series:
    """One curve, set of points or bars: ``x``, ``y``, a name and a colour index (0–2 channels, 3 grey)."""

    name: str
    x: np.ndarray
    y: np.ndarray
    colour: int = 3
    points: bool = True
    bars: bool = False


@dataclass(frozen=True)
class PlotView:
    """A titled plot: axis labels with units, its series, and named x ticks if the x axis is categorical."""

    title: str
    x_label: str
    y_label: str
    series: tuple = ()
    x_ticks: tuple = ()


@dataclass(frozen=True)
class SweepView:
    """One channel's sweep fit (top) and residuals (bottom): baseline vs extended."""

    fit: PlotView
    residuals: PlotView


def XYZ_to_srgb8(XYZ, white_XYZ) -> np.ndarray:
    """XYZ (absolute) → 8-bit sRGB for a swatch on the screen, the display white shown as sRGB white.

    ``XYZ`` is scaled by the white's Y and adapted (Bradford) from the white's
    chromaticity to D65; values outside sRGB are clipped.
    """
    XYZ = np.asarray(XYZ, dtype=float)
    white = np.asarray(white_XYZ, dtype=float)
    rgb = colour.XYZ_to_sRGB(XYZ / white[1], illuminant=xy_of(white[None])[0],
                             chromatic_adaptation_transform="Bradford")
    return np.round(255 * np.clip(np.nan_to_num(rgb), 0, 1)).astype(np.uint8)


_SWEEP_CACHE: dict = {}


def sweep_views(diagnosis) -> tuple:
    """Per channel: measured points with the baseline power law and the extended curve, and residuals.

    The views of the latest diagnosis asked for are kept: the page and the cards ask more than once.
    """
    cached = _SWEEP_CACHE.get("views")
    if cached is not None and cached[0] is diagnosis:
        return cached[1]
    views = _sweep_views(diagnosis)
    _SWEEP_CACHE["views"] = (diagnosis, views)
    return views


def _model_sweep(model, channel: int, drive) -> np.ndarray:
    """A model's single-channel sweep, black subtracted, relative to its own full drive.

    Through the whole model, not the tone curve alone: a power limit dims a sweep by its own
    load, and the sweep-corrected grey ramp applies each channel's ratio on its own axis.
    """
    drive = np.asarray(drive, dtype=float)
    rgb = np.zeros((drive.size + 1, 3))
    rgb[:-1, channel] = 255.0 * np.clip(drive, 0.0, 1.0)
    rgb[-1, channel] = 255.0
    Y = model.forward(rgb)[:, 1] - model.black_XYZ[1]
    return Y[:-1] / Y[-1]


def _sweep_views(diagnosis) -> tuple:
    raw_sweeps = channel_sweeps(diagnosis.context.raw, np.zeros(3))
    extended = diagnosis.extended
    views = []
    for c, sweep in enumerate(diagnosis.context.sweeps):
        raw = raw_sweeps[c]
        gamma = float(diagnosis.baseline.gamma[c])
        # short labels: a narrow plot's legend cuts what does not fit in it
        fit = [Series("measured", raw.drive * 255, raw.output, 3),
               Series(f"baseline γ = {gamma:.2f}", _GRID * 255, _GRID ** gamma, 3, points=False)]
        residuals = [Series("baseline", raw.drive * 255, 100 * (raw.output - raw.drive ** gamma), 3)]
        if hasattr(extended, "tone"):
            curve = extended.tone[c]
            interaction = getattr(extended, "interaction", None)
            bends = interaction is not None and (interaction.load_weights is not None
                                                 or interaction.axis_ratio is not None)
            # the rows the extension is fitted to: black subtracted, and drift corrected too
            # where drift was found
            fit += [Series("drift-corrected" if diagnosis.context.drift_found else "black-subtracted",
                           sweep.drive * 255, sweep.output, c),
                    Series(f"extended ({curve.form}" + (" × interaction)" if bends else ")"),
                           _GRID * 255, _model_sweep(extended, c, _GRID), c, points=False)]
            residuals.append(Series("extended", sweep.drive * 255,
                                    100 * (sweep.output - _model_sweep(extended, c, sweep.drive)), c))
        name = CHANNEL_NAMES[c]
        views.append(SweepView(PlotView(f"{name} sweep", "DAC", "output / full drive", tuple(fit)),
                               PlotView(f"{name} residuals", "DAC", "residual, % of full drive", tuple(residuals))))
    return tuple(views)


def additivity_view(diagnosis) -> PlotView:
    """White vs R + G + B (black subtracted), per tristimulus value, in %."""
    context = diagnosis.context
    ratio = 100 * (context.white - context.black) / sum(s.full_XYZ for s in context.sweeps)
    return PlotView("white / (R + G + B)", "tristimulus value", "white / (R + G + B), %",
                    (Series("measured", np.arange(3.0), ratio, 3, bars=True),
                     Series("additive (100 %)", np.array([-0.5, 2.5]), np.array([100.0, 100.0]), 3, points=False)),
                    x_ticks=((0, "X"), (1, "Y"), (2, "Z")))


def grey_additivity_view(diagnosis) -> PlotView | None:
    """Greys vs the sum of their channels at the same DAC (Y, black subtracted, %), where both were measured."""
    context = diagnosis.context
    session = context.fit
    grey = (session.rgb[:, 0] == session.rgb[:, 1]) & (session.rgb[:, 1] == session.rgb[:, 2]) \
        & (session.rgb[:, 0] > 0) & (session.rgb[:, 0] < 255)
    if not grey.any():
        return None
    level = session.rgb[grey, 0]
    summed = sum(np.interp(level / 255, s.drive, s.XYZ[:, 1], left=np.nan, right=np.nan) for s in context.sweeps)
    measured = session.XYZ[grey, 1] - context.black[1]
    usable = np.isfinite(summed) & (summed > 0.02 * sum(s.full_XYZ[1] for s in context.sweeps))
    if not usable.any():
        return None
    return PlotView("greys / sum of channels", "DAC", "grey Y / (R+G+B) Y, %",
                    (Series("greys", level[usable], 100 * measured[usable] / summed[usable], 3),))


def chromaticity_view(diagnosis) -> PlotView:
    """Each primary's xy distance from its full-drive chromaticity vs drive."""
    series = []
    for c, sweep in enumerate(diagnosis.context.sweeps):
        usable = sweep.output >= 0.02
        distance = np.hypot(*(xy_of(sweep.XYZ[usable]) - sweep.full_xy).T)
        series.append(Series(CHANNEL_NAMES[c], sweep.drive[usable] * 255, distance, c))
    return PlotView("chromaticity vs drive", "DAC", "Δxy from full drive", tuple(series))


def white_reference_view(diagnosis) -> PlotView | None:
    """The white references' Y over the session (% of the settled state; against row order where
    the rows have no times), and the correction as applied where drift was found (smoothed to
    their noise, ramped between them), or None where no two whites can be ordered."""
    drift = diagnosis.context.drift
    if drift is None:
        return None
    scale, x_label, y_label = white_reference_axes(diagnosis.context.time_basis)
    series = (Series("white", drift.times * scale, 100 * drift.gains, 3),)
    if diagnosis.context.drift_found:
        t, gain = drift.sampled()
        series += (Series("correction", t * scale, 100 * gain, 2, points=False),)
    return PlotView("white references", x_label, y_label, series)


@dataclass(frozen=True)
class ValidationRow:
    """A held-out colour: DAC, measured and predicted swatches, ΔE00 of baseline and extended."""

    rgb: tuple
    measured_srgb8: tuple
    baseline_srgb8: tuple
    extended_srgb8: tuple
    baseline_dE00: float
    extended_dE00: float


def validation_rows(diagnosis) -> tuple:
    """The validation colours, worst (extended ΔE00) first; empty without validation colours."""
    validation = diagnosis.session.select("validation")
    if len(validation) == 0 or diagnosis.extended_dE.size != len(validation):
        return ()
    white = diagnosis.white
    extended = diagnosis.extended.forward(validation.rgb)
    if diagnosis.context.drift_found and validation.t_s is not None:
        extended = extended * diagnosis.context.drift.gain(validation.t_s)[:, None]
    measured = XYZ_to_srgb8(validation.XYZ, white)
    baseline = XYZ_to_srgb8(diagnosis.baseline.forward(validation.rgb), white)
    extended = XYZ_to_srgb8(extended, white)
    rows = [ValidationRow(tuple(int(v) for v in validation.rgb[i]), tuple(measured[i]), tuple(baseline[i]),
                          tuple(extended[i]), float(diagnosis.baseline_dE[i]), float(diagnosis.extended_dE[i]))
            for i in range(len(validation))]
    return tuple(sorted(rows, key=lambda r: r.extended_dE00, reverse=True))


def histogram_view(diagnosis, bins: int = 20) -> PlotView | None:
    """ΔE00 histograms of baseline and extended on the same bins (x: bin centres)."""
    if diagnosis.baseline_dE.size == 0:
        return None
    top = float(max(diagnosis.baseline_dE.max(), diagnosis.extended_dE.max()))
    edges = np.linspace(0, top * 1.05 + 1e-9, bins + 1)
    centres = (edges[:-1] + edges[1:]) / 2
    return PlotView("ΔE00 on held-out colours", "ΔE00", "colours",
                    (Series("baseline", centres, np.histogram(diagnosis.baseline_dE, edges)[0].astype(float), 3),
                     Series("extended", centres, np.histogram(diagnosis.extended_dE, edges)[0].astype(float), 2)))


def _tone_plot(diagnosis, result) -> PlotView:
    series = []
    for c, view in enumerate(sweep_views(diagnosis)):
        baseline = view.residuals.series[0]
        series.append(Series(CHANNEL_NAMES[c], baseline.x, baseline.y, c))
    return PlotView("baseline power-law residuals", "DAC", "residual, % of full drive", tuple(series))


def _black_plot(diagnosis, result) -> PlotView:
    """The dark end of the sweeps as measured, where light at DAC 0 shows."""
    series = []
    for c, view in enumerate(sweep_views(diagnosis)):
        measured = view.fit.series[0]
        dark = measured.x <= _DARK_END_DAC
        series.append(Series(CHANNEL_NAMES[c], measured.x[dark], measured.y[dark], c))
    return PlotView("dark end of the sweeps", f"DAC (≤ {_DARK_END_DAC}), as measured", "output / full drive",
                    tuple(series))


_DARK_END_DAC = 64


FINDING_PLOTS = {
    "temporal-drift": lambda d, r: white_reference_view(d),
    "black-offset": _black_plot,
    "channel-interaction": lambda d, r: additivity_view(d),
    "chromaticity-shift": lambda d, r: chromaticity_view(d),
    "tone-curve-shape": _tone_plot,
}
"""Effect id → ``plot(diagnosis, finding_json)``: the evidence plot of its card (None: no plot)."""


@dataclass(frozen=True)
class FindingCard:
    """A finding as a card: its effect, its evidence, every other field as (name, text), and a plot.

    A finding another finding explains has ``consequence_of`` (the cause's effect) and
    ``consequence`` (why, split off the evidence so that it is said once); its cause's card
    lists it in ``consequences``.
    """

    effect: str
    evidence: str
    fields: tuple = ()
    plot: PlotView | None = None
    extra: dict = field(default_factory=dict)
    consequence_of: str = ""
    consequence: str = ""
    consequences: tuple = ()


def _text(value) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, dict):
        return ", ".join(f"{k} {_text(v)}" for k, v in value.items())
    if isinstance(value, list | tuple):
        return ", ".join(_text(v) for v in value)
    return str(value)


def _entries_naming(value, effect: str, path: str):
    """Every dict under ``value`` whose ``effect`` is ``effect``, with where it was found."""
    if isinstance(value, dict):
        if value.get("effect") == effect:
            yield path, value
        for key, item in value.items():
            yield from _entries_naming(item, effect, f"{path}.{key}" if path else key)
    elif isinstance(value, list):
        for item in value:
            yield from _entries_naming(item, effect, path)


HEADLINE_KEYS = ("z", "critical_z", "p_value", "statistic", "standard_error", "impact_dE00",
                 "significant", "testable", "in_model")
"""Statistics a record's headline states in words (:func:`evidence_headline`); not repeated as fields."""


def evidence_headline(record: dict) -> str:
    """A test's result in one line: significance, effect size ± SE, impact, whether it is modelled.

    Uses only what the record has (any of :data:`HEADLINE_KEYS`), so records of
    other shapes give a shorter line, never an error.
    """
    if record.get("testable") is False:  # an untested effect has no statistics to state
        return "not testable"
    parts = []
    z, critical = record.get("z"), record.get("critical_z")
    if isinstance(z, (int, float)):
        test = f"z {z:.1f}"
        if isinstance(critical, (int, float)):
            test += f" {'≥' if z >= critical else '<'} {critical:.2f} (family-wise 5 %)"
        if isinstance(record.get("p_value"), (int, float)):
            test += f", p {record['p_value']:.2g}"
        parts.append(test)
    statistic, error = record.get("statistic"), record.get("standard_error")
    if isinstance(statistic, (int, float)):
        parts.append(f"statistic {statistic:.4g}" + (f" ± {error:.2g}" if isinstance(error, (int, float)) else ""))
    if isinstance(record.get("impact_dE00"), (int, float)):
        parts.append(f"impact {record['impact_dE00']:.2f} ΔE00 on the fixed colours")
    if "in_model" in record:
        parts.append("in the extended model" if record["in_model"] else "not in the model")
    return " · ".join(parts)


def _without_reason(note: str, reason: str) -> str:
    """``note`` with the model choice's ``reason`` at its end said once, in the exported model's table."""
    if not reason or not note.endswith(reason) or note == reason:
        return note
    return note[: -len(reason)].rstrip(" :;,") + " (why: see the exported model above)"


def finding_cards(diagnosis) -> tuple:
    """One card per finding in ``diagnosis.to_json()["findings"]``, with every field it has.

    A ``cross_validation`` note that ends with the model choice's reason says it once, where the
    exported model is shown (the note of every finding the chosen model answers repeats it).
    """
    document = diagnosis.to_json()
    reason = str((document.get("model_choice") or {}).get("reason") or "")
    cards = []
    for finding in document.get("findings", []):
        effect = str(finding.get("effect", "?"))
        fields = [("test", evidence_headline(finding))]
        fields += [(k, _without_reason(_text(v), reason) if k == "cross_validation" else _text(v))
                   for k, v in finding.items()
                   if k not in ("effect", "evidence", "consequence_of", *HEADLINE_KEYS)
                   and v not in (None, "")]
        for where, entry in _entries_naming({k: v for k, v in document.items() if k != "findings"}, effect, ""):
            if entry == finding:  # the same record again (``unexplained``): its fields are on the card
                continue
            fields += [(f"{where}: {k}", _text(v)) for k, v in entry.items()
                       if k != "effect" and v not in (None, "")]
        plot = FINDING_PLOTS.get(effect)
        evidence, why = split_consequence(finding)
        consequences = tuple(str(f.get("effect")) for f in document.get("findings", [])
                             if f.get("consequence_of") == effect)
        cards.append(FindingCard(effect, evidence, tuple(fields),
                                 None if plot is None else plot(diagnosis, finding),
                                 consequence_of=str(finding.get("consequence_of") or ""),
                                 consequence=why, consequences=consequences))
    return tuple(cards)


@dataclass(frozen=True)
class ModelChoiceRow:
    """A candidate model: its id, what it is, its cross-validated mean ΔE00 on the fit rows
    (None: not scored), and whether the profile exports it."""

    candidate: str
    description: str
    cv_mean_dE00: float | None
    chosen: bool


def model_choice_rows(diagnosis) -> tuple:
    """The candidates ``model_choice`` scored, in its order; empty where the diagnosis has no choice."""
    choice = diagnosis.to_json().get("model_choice") or {}
    descriptions = choice.get("candidates") or {}
    return tuple(ModelChoiceRow(str(name), str(descriptions.get(name, "")),
                                None if value is None else float(value), name == choice.get("chosen"))
                 for name, value in (choice.get("cv_mean_dE00") or {}).items())


def model_choice_reason(diagnosis) -> str:
    """Why the exported model was chosen ("" without a choice), and its primaries where they were
    estimated with the white references."""
    choice = diagnosis.to_json().get("model_choice") or {}
    primaries = str(choice.get("primaries") or PRIMARIES_AS_MEASURED)
    reason = str(choice.get("reason") or "")
    return reason if primaries == PRIMARIES_AS_MEASURED else (
        f"{reason.rstrip('.')}. Full-drive primaries {primaries}.")


VERDICT_KEYS = ("session", "baseline", "extended", "gain")
"""Top-level entries of ``to_json()`` that make the one-glance verdict; the others are details."""

SHOWN_APART = ("model_choice",)
"""Top-level entries of ``to_json()`` the page shows in a table of their own, not as detail lines."""


def _scores(block: dict) -> str:
    validation = block.get("validation") or {}
    figures = ", ".join(f"{k.replace('_dE00', '')} {v:.2f}" for k, v in validation.items()
                        if k.endswith("_dE00") and isinstance(v, float))
    return f"{block.get('model', '')}: ΔE00 {figures}" if figures else str(block.get("model", ""))


def summary_lines(diagnosis) -> tuple:
    """The verdict (session, baseline, extended, gain, the exported model) as ``(name, text)`` lines."""
    document = diagnosis.to_json()
    session = document.get("session", {})
    gain = (document.get("gain") or {}).get("mean_dE00_reduction_pct")
    lines = [("session", f"{session.get('source', '')}: {session.get('measurements', '?')} measurements, "
                         f"{session.get('validation', '?')} held out"),
             ("baseline", _scores(document.get("baseline") or {})),
             ("extended", _scores(document.get("extended") or {}))]
    if gain is not None:
        lines.append(("gain", f"mean ΔE00 reduced by {gain:.0f} % on held-out colours"))
    choice = document.get("model_choice") or {}
    if choice.get("chosen"):
        lines.append(("exported", f"{choice['chosen']}, the best of {len(choice.get('cv_mean_dE00') or {})} "
                                  "candidates cross-validated on the fit rows"))
    return tuple(lines)


def _record_line(record: dict) -> str:
    """A record naming an effect as ``effect: headline — evidence`` (or its reason); others as fields."""
    if "effect" not in record:
        return _text(record)
    headline = evidence_headline(record)
    said = record.get("evidence") or record.get("reason") or ""
    rest = {k: v for k, v in record.items()
            if k not in ("effect", "evidence", "reason", "score", "threshold", *HEADLINE_KEYS)
            and v not in (None, "")}
    text = f"{record['effect']}: " + " — ".join(p for p in (headline, str(said)) if p)
    return text + (f" ({_text(rest)})" if rest else "")


def detail_lines(diagnosis) -> tuple:
    """Every other top-level entry of ``to_json()`` (findings and :data:`SHOWN_APART` aside) as
    ``(name, text)``; a list of records gives one line per record."""
    lines = []
    for key, value in diagnosis.to_json().items():
        if key in VERDICT_KEYS or key in SHOWN_APART or key == "findings" or value is None:
            continue
        if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            lines += [(key, _record_line(v)) for v in value]
        else:
            lines.append((key, _text(value)))
    return tuple(lines)


CHECKED_KEYS = ("checked", "untested")
"""Top-level entries of ``to_json()`` the page shows as the table of checked effects (:func:`checked_rows`)."""


@dataclass(frozen=True)
class CheckedRow:
    """An effect that was checked and not found (or could not be tested), as a row of text cells.

    ``test``: z against the critical value (``"0.50 < 2.33"``); ``statistic``: the effect's size ±
    its standard error; ``impact``: mean ΔE00 on the fixed colours; ``model``: whether it is in the
    model, or why not; ``evidence``: everything the diagnosis said about it (the row's tooltip).
    """

    effect: str
    test: str
    statistic: str
    impact: str
    model: str
    evidence: str
    significant: bool = False
    in_model: bool = False
    testable: bool = True


def _number_or_none(value):
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _test_cell(record: dict) -> str:
    z, critical = _number_or_none(record.get("z")), _number_or_none(record.get("critical_z"))
    p_value = _number_or_none(record.get("p_value"))
    if z is None:  # p 1 has no finite z
        left = "—" if p_value is None else f"— (p {p_value:.2g})"
        return left if critical is None else f"{left} / {critical:.2f}"
    if critical is None:
        return f"{z:.2f}"
    return f"{z:.2f} {'≥' if z >= critical else '<'} {critical:.2f}"


def _model_cell(record: dict, floor) -> str:
    if record.get("in_model"):
        note = str(record.get("cross_validation") or "")
        return "yes" + (f": {note}" if note else "")
    impact = _number_or_none(record.get("impact_dE00"))
    if record.get("significant"):
        note = str(record.get("cross_validation") or "")
        if note:
            return f"no: {note}"
        if impact is not None and floor is not None and impact < floor:
            return f"no: significant but immaterial (impact {impact:.2f} < {floor:g} ΔE00)"
        return "no: significant but not material"
    return "no: within noise"


def checked_rows(diagnosis) -> tuple:
    """Every effect in ``to_json()["checked"]``, then every one in ``["untested"]`` not checked, as rows.

    An effect that could not be tested says why (the ``untested`` reason where there is one); the
    others say whether they are in the model and, where not, why (within noise, or immaterial:
    impact below the materiality floor of ``["significance"]``).
    """
    document = diagnosis.to_json()
    floor = _number_or_none((document.get("significance") or {}).get("materiality_floor_dE00"))
    untested = {}
    for entry in document.get("untested") or []:
        if isinstance(entry, dict):
            untested[str(entry.get("effect", "?"))] = str(entry.get("reason") or "")
        else:  # "effect: reason"
            effect, _, reason = str(entry).partition(": ")
            untested[effect] = reason
    rows, seen = [], set()
    for record in document.get("checked") or []:
        if not isinstance(record, dict):
            continue
        effect = str(record.get("effect", "?"))
        seen.add(effect)
        evidence = str(record.get("evidence") or "")
        statistic, error = _number_or_none(record.get("statistic")), _number_or_none(record.get("standard_error"))
        impact = _number_or_none(record.get("impact_dE00"))
        testable = record.get("testable") is not False
        if testable:
            test = _test_cell(record)
            size = ("—" if statistic is None
                    else f"{statistic:.3g}" + (f" ± {error:.2g}" if error is not None else ""))
            model = _model_cell(record, floor)
        else:
            reason = untested.get(effect) or evidence.removeprefix("not testable: ")
            test, size, model = "not testable", "—", f"not testable: {reason}"
        rows.append(CheckedRow(effect, test, size, "—" if impact is None else f"{impact:.2f}", model, evidence,
                               bool(record.get("significant")), bool(record.get("in_model")), testable))
    rows += [CheckedRow(effect, "not tested", "—", "—", f"not tested: {reason}", reason, testable=False)
             for effect, reason in untested.items() if effect not in seen]
    return tuple(rows)
