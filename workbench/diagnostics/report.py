"""A self-contained HTML report of a diagnosis (plots embedded as PNG data URIs).

Sections: the verdict (baseline vs extended on held-out colours), the model
the profile exports (each candidate's cross-validated ΔE00, the chosen one
marked), the session's noise model, the findings with their statistic,
standard error, z and impact (a consequence of another finding indented after
its cause, tagged "consequence of …"), what was checked and not found, what
could not be tested, sweep fits and residuals per channel, the additivity
chart, chromaticity vs level, the white references vs time, and the CIEDE2000
histograms before and after. Plots use matplotlib's Agg canvas directly (no
GUI backend, no global state).
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from workbench import __version__
from workbench.diagnostics.evidence import channel_sweeps, white_reference_axes, xy_of
from workbench.diagnostics.model_choice import PRIMARIES_AS_MEASURED
from workbench.diagnostics.selection import Diagnosis
from workbench.fileio import atomic_writer

__all__ = ["render_report", "write_report", "split_consequence"]

_COLOURS = ("#c0392b", "#27ae60", "#2e6fd0")
_NAMES = ("red", "green", "blue")


def _png(figure: Figure) -> str:
    buffer = io.BytesIO()
    FigureCanvasAgg(figure).print_png(buffer)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def _sweep_figure(diagnosis: Diagnosis) -> Figure:
    figure = Figure(figsize=(11, 6), layout="constrained")
    axes = figure.subplots(2, 3, sharex=True)
    grid = np.linspace(0, 1, 256)
    extended = diagnosis.extended
    raw_sweeps = channel_sweeps(diagnosis.context.raw, np.zeros(3))
    for c, sweep in enumerate(diagnosis.context.sweeps):
        top, bottom = axes[0, c], axes[1, c]
        raw = raw_sweeps[c]
        gamma = diagnosis.baseline.gamma[c]
        top.plot(raw.drive * 255, raw.output, "o", ms=3, mfc="none", color="0.5",
                 label="as measured (baseline's data)")
        top.plot(grid * 255, grid ** gamma, "k--", lw=1, label=f"baseline power γ={gamma:.2f}")
        bottom.plot(raw.drive * 255, 100 * (raw.output - raw.drive ** gamma), "k.", label="baseline")
        if hasattr(extended, "tone"):
            curve = extended.tone[c]
            top.plot(sweep.drive * 255, sweep.output, "o", ms=3, color=_COLOURS[c],
                     label="black subtracted" + (", drift corrected" if diagnosis.context.drift_found else ""))
            top.plot(grid * 255, curve.forward(grid), color=_COLOURS[c], lw=1.5,
                     label=f"extended ({curve.form})")
            bottom.plot(sweep.drive * 255, 100 * (sweep.output - curve.forward(sweep.drive)), ".",
                        color=_COLOURS[c], label="extended")
        top.set_title(f"{_NAMES[c]} sweep")
        top.set_ylabel("output / full")
        bottom.set_ylabel("residual, % of full")
        bottom.set_xlabel("DAC")
        bottom.axhline(0, color="0.7", lw=0.8)
        top.legend(fontsize=7)
        bottom.legend(fontsize=7)
    return figure


def _additivity_figure(diagnosis: Diagnosis) -> Figure:
    context = diagnosis.context
    summed = sum(s.full_XYZ for s in context.sweeps)
    white = context.white - context.black
    figure = Figure(figsize=(5, 3.2), layout="constrained")
    axis = figure.subplots()
    axis.bar(["X", "Y", "Z"], 100 * white / summed, color=["#999", "#555", "#999"])
    axis.axhline(100, color="k", lw=1)
    axis.set_ylabel("white / (R + G + B), %")
    axis.set_ylim(min(90, float(np.min(100 * white / summed)) - 2),
                  max(110, float(np.max(100 * white / summed)) + 2))
    axis.set_title("additivity (black subtracted)")
    return figure


def _chromaticity_figure(diagnosis: Diagnosis) -> Figure:
    figure = Figure(figsize=(11, 3.2), layout="constrained")
    axes = figure.subplots(1, 3)
    for c, sweep in enumerate(diagnosis.context.sweeps):
        usable = sweep.output >= 0.02
        xy = xy_of(sweep.XYZ[usable])
        distance = np.hypot(*(xy - sweep.full_xy).T)
        axes[c].plot(sweep.drive[usable] * 255, distance, "o-", ms=3, color=_COLOURS[c])
        axes[c].set_title(f"{_NAMES[c]}: Δxy from full drive")
        axes[c].set_xlabel("DAC")
        axes[c].set_ylabel("Δxy")
    return figure


def _drift_figure(diagnosis: Diagnosis) -> Figure | None:
    drift = diagnosis.context.drift
    if drift is None:
        return None
    figure = Figure(figsize=(5, 3.2), layout="constrained")
    axis = figure.subplots()
    scale, x_label, y_label = white_reference_axes(diagnosis.context.time_basis)
    axis.plot(drift.times * scale, 100 * drift.gains, "o", color="#444", label="white references")
    if diagnosis.context.drift_found:
        # the correction as applied: the references smoothed to their noise, ramped between them
        t, gain = drift.sampled()
        axis.plot(t * scale, 100 * gain, "-", color="#2e6fd0", label="correction")
        axis.legend(fontsize="small")
    axis.set_xlabel(x_label)
    axis.set_ylabel(y_label)
    axis.set_title("white references vs time")
    return figure


def _histogram_figure(diagnosis: Diagnosis) -> Figure | None:
    if diagnosis.baseline_dE.size == 0:
        return None
    figure = Figure(figsize=(5.5, 3.2), layout="constrained")
    axis = figure.subplots()
    top = float(max(diagnosis.baseline_dE.max(), diagnosis.extended_dE.max()))
    bins = np.linspace(0, top * 1.05 + 1e-9, 25)
    axis.hist(diagnosis.baseline_dE, bins=bins, alpha=0.6, label="baseline", color="#888")
    axis.hist(diagnosis.extended_dE, bins=bins, alpha=0.7, label="extended", color="#2e6fd0")
    axis.set_xlabel("CIEDE2000 on held-out colours")
    axis.set_ylabel("colours")
    axis.legend()
    return figure


def _score_row(label: str, model: str, score) -> str:
    if score is None:
        return f"<tr><td>{label}</td><td>{html.escape(model)}</td><td colspan=3>no validation colours</td></tr>"
    return (f"<tr><td>{label}</td><td>{html.escape(model)}</td><td>{score.mean_dE00:.2f}</td>"
            f"<td>{score.p95_dE00:.2f}</td><td>{score.max_dE00:.2f}</td></tr>")


def split_consequence(finding: dict) -> tuple[str, str]:
    """A finding's own evidence and, where it is another finding's consequence, why (else "").

    ``finding`` is a finding of ``Diagnosis.to_json()``. The evidence of a consequence ends with
    "; a consequence of CAUSE, WHY" (one sentence for the JSON); the terminal, this report and
    the window show WHY apart, under the finding marked as CAUSE's consequence, so it is said once.
    """
    cause = finding.get("consequence_of")
    evidence = str(finding.get("evidence", ""))
    if not cause:
        return evidence, ""
    own, marker, why = evidence.partition(f"; a consequence of {cause}, ")
    return (own, why) if marker else (evidence, "")


def _model_choice_section(choice: dict | None) -> str:
    """Which model the profile exports: each candidate's cross-validated ΔE00, the chosen one marked."""
    if not choice:
        return ""
    descriptions = choice.get("candidates") or {}
    rows = "".join(
        f"<tr{' class=chosen' if name == choice['chosen'] else ''}><td>{html.escape(name)}</td>"
        f"<td>{html.escape(descriptions.get(name, ''))}</td>"
        f"<td class=num>{'—' if value is None else f'{value:.3f}'}</td>"
        f"<td>{'✓ exported' if name == choice['chosen'] else ''}</td></tr>"
        for name, value in choice["cv_mean_dE00"].items())
    return (f"<h2>Exported model: {html.escape(choice['chosen'])}</h2>"
            "<table><tr><th>candidate</th><th>what it is</th><th>cross-validated mean ΔE00 "
            f"(fit rows)</th><th></th></tr>{rows}</table>"
            f"<p>{html.escape(choice['reason'].rstrip('.'))}.</p>"
            f"<p>Full-drive primaries "
            f"{html.escape(choice.get('primaries') or PRIMARIES_AS_MEASURED)}.</p>")


def render_report(diagnosis: Diagnosis) -> str:
    """The report as one HTML string."""
    findings = diagnosis.findings
    terms = {t["effect"]: t for t in diagnosis.to_json()["extended"]["terms"]}
    def model_note(f) -> str:
        if f.effect in terms:
            return (f"extended with {html.escape(terms[f.effect]['term'])}, fitted on "
                    f"{html.escape(terms[f.effect]['fitted_on'])}")
        return html.escape(f.cross_validation or "reported only: it names no model term")

    def item(f) -> str:
        cause = f.details.get("consequence_of")
        evidence, why = split_consequence({"evidence": f.evidence, "consequence_of": cause})
        tag = (f" <span class='tag'>consequence of {html.escape(cause)}</span>" if cause else "")
        because = f"<br><span class='why'>← {html.escape(why)}</span>" if why else ""
        return (f"<li{' class=consequence' if cause else ''}><b>{html.escape(f.effect)}</b>{tag} "
                f"(statistic {f.statistic:.4g} ± {f.standard_error:.2g}, z {f.z:.1f} against "
                f"{f.critical_z:.2f}, impact {f.impact_dE00:.2f} ΔE00; score {f.score:.1f}): "
                f"{html.escape(evidence)}{because}<br><small>{model_note(f)}</small></li>")

    items = "".join(item(f) for f in findings) or (
        "<li>None beyond noise: the paper's model is adequate.</li>")
    not_found = "".join(
        f"<li>{html.escape(r.effect)} (statistic {r.statistic:.4g} ± {r.standard_error:.2g}, "
        f"z {r.z:.1f} against {r.critical_z:.2f}"
        + (f", impact {r.impact_dE00:.3f} ΔE00 below the floor" if r.impact_dE00 is not None
           else "") + f"): {html.escape(r.evidence)}</li>"
        for r in diagnosis.results if not r.found and r.testable)
    untested = "".join(f"<li>{html.escape(effect)}: {html.escape(why)}</li>"
                       for effect, why in diagnosis.untested)
    document = diagnosis.to_json()
    significance = document["significance"]
    gain = diagnosis.gain_pct
    figures = [("Sweep fits and residuals", _sweep_figure(diagnosis)),
               ("Additivity", _additivity_figure(diagnosis)),
               ("Chromaticity vs level", _chromaticity_figure(diagnosis)),
               ("White references vs time", _drift_figure(diagnosis)),
               ("CIEDE2000 before and after", _histogram_figure(diagnosis))]
    images = "".join(f"<h2>{title}</h2><img alt='{title}' src='{_png(figure)}'>"
                     for title, figure in figures if figure is not None)
    apl = ("" if diagnosis.apl is None else
           "<h2>APL curve (load term)</h2><ul>"
           + "".join(f"<li>{html.escape(h.one_line())}</li>" for h in diagnosis.apl.holdouts)
           + "</ul><p>The model holds at the reference load (each patch full field); a patch "
             "on a frame of load L shows gain(L)/gain(L_ref) of its prediction.</p>")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>Display diagnosis — {html.escape(Path(diagnosis.session.source).name)}</title>
<style>body{{font-family:system-ui,sans-serif;max-width:1150px;margin:2em auto;color:#222}}
table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:4px 10px;text-align:left}}
img{{max-width:100%}}.gain{{font-size:1.3em}}
li{{margin-bottom:.5em}}li.consequence{{margin-left:2em;padding-left:.8em;border-left:3px solid #c9c2ad}}
.tag{{font-size:.85em;background:#ece6d6;border-radius:3px;padding:0 .4em;white-space:nowrap}}
.why{{color:#555;font-style:italic}}tr.chosen{{font-weight:bold;background:#eef4e8}}
td.num{{text-align:right}}</style></head><body>
<h1>Display diagnosis</h1>
<p>Session <code>{html.escape(diagnosis.session.source)}</code>: {len(diagnosis.session)} measurements,
{int(diagnosis.session.mask("validation").sum())} validation colours held out (protocol
<b>{diagnosis.protocol}</b>: neither model was fitted on them).</p>
<table><tr><th></th><th>model</th><th>mean ΔE00</th><th>p95</th><th>max</th></tr>
{_score_row("baseline", diagnosis.baseline.describe(), diagnosis.baseline_score)}
{_score_row("extended", diagnosis.extended.describe(), diagnosis.extended_score)}</table>
<p class="gain">{"" if gain is None else f"Mean ΔE00 reduced by <b>{gain:.0f} %</b> on held-out colours."}</p>
{_model_choice_section(document.get("model_choice"))}
<p>CIEDE2000 in CIELAB whose white is the measured display white.</p>
<h2>Noise</h2><p>{html.escape(document["noise"]["summary"])}.</p>
<p>A finding needs z above the family-wise critical value ({100 * significance["family_alpha"]:.0f} %
chance of any false finding in a clean session, {html.escape(significance["method"])}) and an
impact of at least {significance["materiality_floor_dE00"]:g} mean ΔE00 on a
{html.escape(significance["materiality_colours"])}; a term enters the model only where it
improves a {diagnosis.cross_validation.get("folds", 5)}-fold cross-validated prediction of the fit rows.</p>
<h2>Findings</h2><ol>{items}</ol>
<h3>Checked, not found</h3><ul>{not_found or "<li>—</li>"}</ul>
<h3>Not tested</h3><ul>{untested or "<li>—</li>"}</ul>
{apl}
{images}
<p><small>vr-colour-workbench {__version__}</small></p></body></html>
"""


def write_report(diagnosis: Diagnosis, path) -> Path:
    """Write the report atomically."""
    path = Path(path)
    text = render_report(diagnosis)
    with atomic_writer(path) as handle:
        handle.write(text)
    return path
