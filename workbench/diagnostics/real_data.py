"""The real-data table: every measured display in ``shared/data/real/``, diagnosed, beside Argyll.

For each file :func:`read_session` can read (``.ti3``, Psychtoolbox ``.mat``,
and any other format a reader is registered for), :func:`real_data_table`
runs :func:`~workbench.diagnostics.diagnose`,
:func:`~workbench.diagnostics.argyll.score_argyll` and
:func:`~workbench.diagnostics.authors.score_authors_method` on the same session:
the findings with z and impact, baseline / exported (and which model was
chosen) / fallback held-out mean and p95 ΔE00, ArgyllCMS's shaper + matrix
profile and the seed authors' grey-ramp linearisation (where the file has a
grey ramp), each fitted on exactly the same fit rows and scored on the same
held-out rows. The OLED brightness-limiting
sets (``oled-apl/``: the Samsung ``.mat``, the AW3225QF ColorChecker
directory and one entry per white-window preset) have no full-field ramps:
they are diagnosed for ``apl-dependence`` alone
(:func:`~workbench.diagnostics.load_only.diagnose_what_it_can`), with the APL
curve's held-out error (leave one window size or surround level out). ``python -m workbench bench
real-data`` prints it (``--markdown`` for the README's table).

The folder is ``$VR_WORKBENCH_SHARED/data/real`` or ``shared/data/real``
beside the checkout.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from workbench.errors import InputError, SpectrumFileError

__all__ = ["RealDataRow", "RealDataTable", "default_real_data_folder", "real_data_files",
           "real_data_table"]


def default_real_data_folder() -> Path:
    """``$VR_WORKBENCH_SHARED/data/real``, else ``shared/data/real`` beside the checkout."""
    shared = os.environ.get("VR_WORKBENCH_SHARED")
    root = Path(shared) if shared else Path(__file__).resolve().parents[3] / "shared"
    return root / "data" / "real"


def real_data_files(folder: Path) -> list[Path]:
    """Every file under ``folder`` a session reader is registered for (sorted), and the APL sets.

    Directories are excluded unless an APL reader reads them (the AW3225QF
    ColorChecker windows); of the AW3225QF white-window CSVs, one per preset
    (its reader reads every window size of the preset).
    """
    from workbench.apl.readers import apl_session_reader, preset_of_white_window_file
    from workbench.session_readers import SESSION_READERS

    files = [path for path in folder.rglob("*") if path.is_file()
             and path.suffix.lower() in SESSION_READERS and path.suffix.lower() != ".json"
             and path.suffix.lower() != ".csv"]
    files += [path for path in folder.rglob("*") if path.is_dir() and apl_session_reader(path)]
    presets = {}
    for path in sorted(folder.rglob("*.csv")):
        preset = preset_of_white_window_file(path)
        if preset is not None:
            presets.setdefault((path.parent, preset), path)
    return sorted(files + list(presets.values()))


@dataclass(frozen=True)
class RealDataRow:
    file: str
    measurements: int = 0
    validation: int = 0
    findings: tuple = ()  # (effect, z, impact ΔE00, in model)
    untested: tuple = ()
    baseline: dict | None = None
    extended: dict | None = None
    fallback: dict | None = None
    fallback_protocol: str = ""
    argyll: dict | None = None
    authors: dict | None = None
    model_choice: str = ""
    apl_holdout: tuple = ()  # (by, % luminance, ΔE00, without: % luminance, ΔE00)
    noise: str = ""
    error: str = ""
    seconds: float = 0.0

    @property
    def best_ours(self) -> tuple[str, float] | None:
        """(label, mean ΔE00) of the extended model or, where better, the labelled fallback."""
        options = []
        if self.extended is not None:
            options.append(("extended", self.extended["mean_dE00"]))
        if self.fallback is not None:
            options.append(("fallback", self.fallback["mean_dE00"]))
        return min(options, key=lambda o: o[1]) if options else None

    @property
    def beats_argyll(self) -> bool | None:
        if self.argyll is None or self.argyll.get("mean_dE00") is None or self.best_ours is None:
            return None
        return self.best_ours[1] < self.argyll["mean_dE00"]

    @property
    def authors_margin(self) -> float | None:
        """Exported model's held-out mean ΔE00 less the seed authors' method's (None: no greys)."""
        if (self.authors is None or self.authors.get("mean_dE00") is None
                or self.extended is None):
            return None
        return self.extended["mean_dE00"] - self.authors["mean_dE00"]

    @property
    def extended_not_worse(self) -> bool | None:
        if self.extended is None or self.baseline is None:
            return None
        return self.extended["mean_dE00"] <= self.baseline["mean_dE00"] + 1e-9

    def to_json(self) -> dict:
        return {"file": self.file, "measurements": self.measurements,
                "validation": self.validation,
                "findings": [{"effect": e, "z": z, "impact_dE00": i, "in_model": m}
                             for e, z, i, m in self.findings],
                "untested": list(self.untested), "baseline": self.baseline,
                "extended": self.extended, "fallback": self.fallback,
                "fallback_protocol": self.fallback_protocol, "argyll": self.argyll,
                "authors": self.authors, "model_choice": self.model_choice or None,
                "exported_minus_authors_dE00": self.authors_margin,
                "apl_holdout": [{"by": by, "luminance_error_pct": lum, "mean_dE00": dE,
                                 "without_load_term": {"luminance_error_pct": lum0,
                                                       "mean_dE00": dE0}}
                                for by, lum, dE, lum0, dE0 in self.apl_holdout],
                "noise": self.noise, "beats_argyll": self.beats_argyll,
                "extended_not_worse_than_baseline": self.extended_not_worse,
                "error": self.error or None, "seconds": self.seconds}


def _figures(block: dict | None) -> str:
    if block is None or block.get("mean_dE00") is None:
        return "—"
    return f"{block['mean_dE00']:.2f} / {block['p95_dE00']:.2f}"


@dataclass(frozen=True)
class RealDataTable:
    folder: str
    rows: tuple = field(default_factory=tuple)

    def to_json(self) -> dict:
        return {"folder": self.folder, "rows": [row.to_json() for row in self.rows],
                "convention": "held-out mean / p95 CIEDE2000, CIELAB white the measured display "
                              "white; Argyll fitted on exactly the fit rows"}

    def markdown(self) -> str:
        lines = ["| file | findings (z, impact ΔE00; * in the model) | baseline | exported "
                 "(model chosen) | fallback (residual LUT) | Argyll shaper + matrix | authors' grey "
                 "ramp | ours vs Argyll |",
                 "|---|---|---|---|---|---|---|---|"]
        for row in self.rows:
            if row.error:
                continue
            findings = ", ".join(f"{e}{'*' if m else ''} (z {z:.1f}, {i:.2f})"
                                 for e, z, i, m in row.findings) or "none"
            argyll = (_figures(row.argyll) if row.argyll and row.argyll.get("mean_dE00") is not None
                      else (row.argyll or {}).get("unavailable") or "—")
            verdict = ("—" if row.beats_argyll is None else
                       f"better ({row.best_ours[0]})" if row.beats_argyll else "worse")
            authors = (_figures(row.authors) if row.authors and row.authors.get("mean_dE00")
                       is not None else "—")
            lines.append(f"| `{row.file}` | {findings} | {_figures(row.baseline)} | "
                         f"{_figures(row.extended)} ({row.model_choice or 'extension'}) | "
                         f"{_figures(row.fallback)} | {argyll} | {authors} | {verdict} |")
        lines.append("")
        held = [r for r in self.rows if r.apl_holdout and not r.error]
        if held:
            lines.append("APL curve held out (leave one condition out; mean error in % of "
                         "luminance / ΔE00, without a load term in brackets): "
                         + "; ".join(f"`{r.file}` " + ", ".join(
                             f"by {by} {lum:.1f} % / {dE:.2f} ({lum0:.1f} % / {dE0:.2f})"
                             for by, lum, dE, lum0, dE0 in r.apl_holdout) for r in held) + ".")
            lines.append("")
        lines.append("Mean / p95 ΔE00 on the held-out (validation) colours; fallback protocols: "
                     + "; ".join(f"`{r.file}` {r.fallback_protocol.split(':')[0]}" for r in self.rows
                                 if r.fallback_protocol) + ".")
        unread = [r for r in self.rows if r.error]
        if unread:
            lines.append("Not diagnosed: "
                         + "; ".join(f"`{r.file}` ({r.error})" for r in unread) + ".")
        return "\n".join(lines)

    def summary(self) -> str:
        lines = [f"real data in {self.folder}:"]
        for row in self.rows:
            if row.error:
                lines.append(f"  {row.file}: not diagnosed ({row.error})")
                continue
            findings = ", ".join(f"{e} (z {z:.1f}, impact {i:.2f}{', in model' if m else ''})"
                                 for e, z, i, m in row.findings) or "none"
            argyll = (_figures(row.argyll) if row.argyll and row.argyll.get("mean_dE00") is not None
                      else (row.argyll or {}).get("unavailable") or "—")
            lines.append(f"  {row.file} ({row.measurements} rows, {row.validation} held out, "
                         f"{row.seconds:.1f} s)")
            lines.append(f"    findings: {findings}")
            lines.append(f"    held-out mean / p95 ΔE00: baseline {_figures(row.baseline)}, "
                         f"exported ({row.model_choice or 'extension'}) {_figures(row.extended)}, "
                         f"fallback {_figures(row.fallback)}, Argyll shaper + matrix {argyll}, "
                         f"authors' grey ramp "
                         f"{_figures(row.authors) if row.authors else '—'}"
                         + ("" if row.beats_argyll is None else
                            f" → ours {'beats' if row.beats_argyll else 'does not beat'} Argyll"))
            for by, lum, dE, lum0, dE0 in row.apl_holdout:
                lines.append(f"    APL curve, leave one {by} out: {lum:.1f} % of luminance, "
                             f"{dE:.2f} ΔE00 (without a load term {lum0:.1f} %, {dE0:.2f})")
        return "\n".join(lines)


def _row(path: Path, folder: Path, with_argyll: bool) -> RealDataRow:
    from workbench.diagnostics.argyll import ArgyllError, score_argyll
    from workbench.diagnostics.authors import score_authors_method
    from workbench.diagnostics.load_only import LoadOnlyDiagnosis, diagnose_what_it_can
    from workbench.session_readers import read_session

    name = str(path.relative_to(folder))
    started = time.perf_counter()
    try:
        session = read_session(path)
        diagnosis = diagnose_what_it_can(session)
    except (InputError, SpectrumFileError, ValueError) as error:
        # the first clause of the message, the file by its name in the table
        reason = str(error).splitlines()[0].split("; ")[0].replace(str(path), name)
        return RealDataRow(file=name, error=reason)
    document = diagnosis.to_json()
    argyll = None
    load_only = isinstance(diagnosis, LoadOnlyDiagnosis)
    if with_argyll and load_only:
        argyll = {"unavailable": "no full-field ramps to fit a profile on", "mean_dE00": None}
    elif with_argyll:
        try:
            argyll = score_argyll(session).to_json()
        except ArgyllError as error:
            argyll = {"unavailable": str(error), "mean_dE00": None}
    fallback = document["fallback"]
    authors = None
    if not load_only:
        score = score_authors_method(session)
        authors = None if score.unavailable else score.to_json()
    return RealDataRow(
        file=name, measurements=len(session), validation=int(session.mask("validation").sum()),
        findings=tuple((f["effect"], f["z"] or 0.0, f["impact_dE00"] or 0.0, f["in_model"])
                       for f in document["findings"]),
        untested=tuple(f"{u['effect']}: {u['reason']}" for u in document["untested"]),
        baseline=None if load_only else document["baseline"]["validation"],
        extended=None if load_only else document["extended"]["validation"],
        fallback=None if fallback is None else fallback["validation"],
        fallback_protocol="" if fallback is None else fallback["protocol"], argyll=argyll,
        authors=authors,
        model_choice=((document.get("model_choice") or {}).get("chosen") or ""),
        apl_holdout=tuple((h["by"], h["luminance_error_pct"], h["mean_dE00"],
                           h["without_load_term"]["luminance_error_pct"],
                           h["without_load_term"]["mean_dE00"])
                          for h in ((document.get("apl") or {}).get("holdout") or [])),
        noise=document["noise"]["summary"], seconds=time.perf_counter() - started)


def real_data_table(folder=None, with_argyll: bool = True) -> RealDataTable:
    """Diagnose every readable file under ``folder`` (default :func:`default_real_data_folder`)."""
    folder = Path(folder) if folder is not None else default_real_data_folder()
    if not folder.is_dir():
        raise InputError(f"no real-data folder at {folder}; set VR_WORKBENCH_SHARED to the "
                         "shared/ folder that holds data/real")
    return RealDataTable(folder=str(folder),
                         rows=tuple(_row(path, folder, with_argyll)
                                    for path in real_data_files(folder)))
