"""The measurement runner: show each patch, measure it, journal it (no Qt).

:class:`MeasurementRun` is a generator worker in the style of napari's
``GeneratorWorker`` and pymeasure's ``Procedure``: iterating :meth:`MeasurementRun.events`
performs the run and yields one event per step (:class:`RunStarted`,
:class:`PatchStarted`, :class:`PatchMeasured`, :class:`RunPaused`,
:class:`RunResumed`, and last :class:`RunFinished`). The same run drives the
command line (a tqdm bar) and the GUI (a worker thread); :meth:`pause`,
:meth:`resume` and :meth:`cancel` may be called from any thread.

For each pending patch of the plan the runner shows it on the
:class:`~instruments.patch_display.PatchDisplay`, measures it with the meter
(the CS-2000 driver, or anything with the same ``identify``/``measure``), and
appends a record to the journal (flushed and fsynced before the next patch).
Then:

* a patch that fails after the instrument's own recovery (an instrument error
  code, a timeout) is journaled as ``failed`` with the reason and the run
  continues; after :attr:`MeasurementRun.max_consecutive_failures` failures in
  a row the run stops (:class:`RunAborted`), since the instrument needs a look;
* the instrument's port vanishing, or the patch display failing, stops the run
  with :class:`RunAborted`, naming the patch; the journal keeps every earlier
  measurement, and a resumed run starts with that patch;
* a resumed run measures the patches that have no record yet and those whose
  latest attempt failed, never one that was measured, unless it is asked to
  re-measure it (``remeasure``): the journal then keeps both records, the
  newer one wins (:meth:`~workbench.measurement.journal.Journal.latest`), and
  the resume record names the patches re-measured;
* at the end the session is exported as ``session.csv`` (with ``nm380`` …
  ``nm780`` spectral columns) and ``session.ti3``.

A measurement whose spectrum the instrument could not compute (its "not
computable" placeholders, NaN in the driver's result) keeps its XYZ, ``Lv`` and
``xy`` but not the spectrum, and its journal record says so in ``warning``; if
XYZ are not computable either, the patch fails with that reason.

Times: ``t_s`` in the journal is the session clock's reading when the patch was
shown (:class:`SessionClock`: wall-clock seconds since the session began for a
real instrument; the modelled instrument time for a simulated one); progress
ETAs are wall-clock seconds (the runner's ``wall_clock``, :func:`time.monotonic`
by default) from :class:`~workbench.measurement.eta.PatchDurationModel`.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Protocol

import numpy as np

from instruments.cs2000 import CS2000Error, MeasurementCancelled, PortVanishedError
from instruments.patch_display import PatchDisplayError, show_patch
from workbench.errors import InputError, WorkbenchError
from workbench.measurement.eta import PatchDurationModel
from workbench.measurement.journal import (
    Journal,
    JournalHeader,
    JournalRecord,
    JournalWriter,
    added_plan_json,
    journal_to_session,
    read_journal,
)
from workbench.measurement.plans import MeasurementPlan, Patch
from workbench.measurement.ti3 import write_session_ti3
from workbench.session import write_session_csv

__all__ = [
    "JOURNAL_NAME",
    "SESSION_CSV_NAME",
    "SESSION_TI3_NAME",
    "Meter",
    "SessionClock",
    "WallSessionClock",
    "RunAborted",
    "RunStarted",
    "PatchStarted",
    "PatchMeasured",
    "RunPaused",
    "RunResumed",
    "RunSummary",
    "RunFinished",
    "MeasurementRun",
    "format_duration",
]

_LOG = logging.getLogger(__name__)

JOURNAL_NAME = "journal.jsonl"
"""File name of the journal in the output directory."""
SESSION_CSV_NAME = "session.csv"
"""File name of the exported session CSV."""
SESSION_TI3_NAME = "session.ti3"
"""File name of the exported Argyll ``.ti3``."""

_PAUSE_POLL_S = 0.1  # how often a paused run looks at its cancel flag


class Meter(Protocol):
    """What the runner needs of an instrument (the CS-2000 driver has it)."""

    def identify(self) -> Any:
        """An object with ``name``, ``model`` and ``serial``."""

    def measure(self, progress: Callable[[float, float], None] | None = None, cancel: Any = None) -> Any:
        """A measurement with ``XYZ``, ``Lv``, ``xy``, ``wavelengths``, ``radiance``,
        ``integration_s`` and ``nd_used``; honours ``cancel`` (raises
        :class:`~instruments.cs2000.MeasurementCancelled`)."""


class SessionClock(Protocol):
    """Seconds since the session began."""

    def now(self) -> float:
        ...


@dataclass(frozen=True)
class WallSessionClock:
    """Wall-clock seconds since ``started_epoch_s`` (the journal header's start).

    A resumed session keeps counting from the original start, gap included:
    the display stayed on (or cooled down) in between, and ``t_s`` says so.
    """

    started_epoch_s: float

    def now(self) -> float:
        return time.time() - self.started_epoch_s


class RunAborted(WorkbenchError):
    """The run had to stop (port vanished, display lost, repeated failures).

    Attributes
    ----------
    index : int
        Plan index of the patch that was in flight.
    patch : Patch
    """

    def __init__(self, message: str, index: int, patch: Patch):
        super().__init__(message)
        self.index, self.patch = index, patch


@dataclass(frozen=True)
class RunStarted:
    """The run begins: ``done`` of ``total`` patches are already measured (resume)."""

    total: int
    done: int
    resumed: bool


@dataclass(frozen=True)
class PatchStarted:
    """Patch ``index`` is about to be shown; ``eta_s`` estimates the rest of the run."""

    index: int
    patch: Patch
    done: int
    total: int
    eta_s: float | None


@dataclass(frozen=True)
class PatchMeasured:
    """Patch ``index`` was measured (or failed) and journaled."""

    record: JournalRecord
    done: int
    total: int
    eta_s: float | None


@dataclass(frozen=True)
class RunPaused:
    """The run is paused before the patch ``next_index``."""

    done: int
    total: int
    next_index: int


@dataclass(frozen=True)
class RunResumed:
    """A paused run continues."""

    done: int
    total: int


@dataclass(frozen=True)
class RunSummary:
    """How a run ended.

    Attributes
    ----------
    status : str
        ``"finished"`` or ``"cancelled"``.
    planned : int
        Patches in the plan.
    measured : int
        Patches with a successful measurement (this run and earlier ones).
    failed : tuple of JournalRecord
        Patches whose latest attempt failed.
    session_s : float
        Session-clock time at the end (simulated time for a simulated instrument).
    wall_s : float
        Wall-clock time this run (this process) took.
    outputs : tuple of Path
        Files written (journal, session CSV, ``.ti3``).
    """

    status: str
    planned: int
    measured: int
    failed: tuple
    session_s: float
    wall_s: float
    outputs: tuple = field(default_factory=tuple)

    def one_line(self, session_label: str = "session") -> str:
        """E.g. ``finished: 214 of 214 patches measured, 0 failed; session 2 h 13 min, wall 12.3 s``."""
        failed = "; ".join(f"{_where(r.index, r.patch(), self.planned)}: {r.reason}" for r in self.failed)
        return (
            f"{self.status}: {self.measured} of {self.planned} patches measured, "
            f"{len(self.failed)} failed{' (' + failed + ')' if failed else ''}; "
            f"{session_label} {format_duration(self.session_s)}, wall {format_duration(self.wall_s)}"
        )


@dataclass(frozen=True)
class RunFinished:
    """The last event of a run that was not aborted."""

    summary: RunSummary


def format_duration(seconds: float) -> str:
    """``"2 h 13 min"``, ``"4 min 05 s"``, ``"12.3 s"``."""
    if seconds >= 3600:
        return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60):02d} min"
    if seconds >= 60:
        return f"{int(seconds // 60)} min {int(seconds % 60):02d} s"
    return f"{seconds:.1f} s"


def _where(index: int, patch: Patch, total: int) -> str:
    """How messages name a patch: ``patch 5 of 28 (ramp-r (153, 0, 0), journal index 4)``."""
    return f"patch {index + 1} of {total} ({patch.describe()}, journal index {index})"


def _nm_ranges(wavelengths) -> str:
    """``"380-384, 779-780 nm"`` for a sorted list of whole wavelengths."""
    values = [int(round(w)) for w in wavelengths]
    ranges, start = [], None
    for i, w in enumerate(values):
        if start is None:
            start = w
        if i + 1 == len(values) or values[i + 1] != w + 1:
            ranges.append(f"{start}" if start == w else f"{start}-{w}")
            start = None
    return ", ".join(ranges) + " nm"


def _finite_or_none(values) -> list | None:
    values = [float(v) for v in np.ravel(values)]
    return values if all(math.isfinite(v) for v in values) else None


class MeasurementRun:
    """A crash-safe measurement run over a plan.

    Create it with :meth:`start` (a new session) or :meth:`resume_session`
    (continue the journal in an output directory), then iterate :meth:`events`.

    Parameters
    ----------
    out_dir : Path
        Holds ``journal.jsonl``, ``session.csv`` and ``session.ti3``.
    journal : Journal or None
        The journal read back when resuming.
    writer : JournalWriter
    display : PatchDisplay
    meter : Meter
    clock : SessionClock
    on_countdown : callable, optional
        ``on_countdown(remaining_s, total_s)`` while the instrument measures.
    settle_s : float
        Seconds to wait after the display confirms a patch before measuring.
    max_consecutive_failures : int
        Stop the run after this many failed patches in a row.
    wall_clock : callable
        Monotonic wall-clock seconds, for the time each patch takes (the ETA)
        and the run's wall time; :func:`time.monotonic` by default.
    planner : object, optional
        A dynamic plan (:class:`~workbench.measurement.adaptive.AdaptivePlanner`):
        once every patch of the plan so far has been tried, the run calls
        ``planner.decide(journal)`` with :meth:`journal_so_far`; a decision
        with patches is journaled (a ``decision`` record, fsynced) and its
        patches are measured next; ``None`` ends the run.
    """

    def __init__(self, out_dir: Path, header: JournalHeader, journal: Journal | None, writer: JournalWriter,
                 display, meter: Meter, clock: SessionClock, *,
                 on_countdown: Callable[[float, float], None] | None = None,
                 settle_s: float = 0.0, max_consecutive_failures: int = 3,
                 wall_clock: Callable[[], float] = time.monotonic, remeasure=(), planner=None):
        self.out_dir = Path(out_dir)
        self.header = header
        self.plan: MeasurementPlan = header.plan
        self.display = display
        self.meter = meter
        self.clock = clock
        self.on_countdown = on_countdown
        self.settle_s = float(settle_s)
        self.max_consecutive_failures = int(max_consecutive_failures)
        self.wall_clock = wall_clock
        self._writer = writer
        self._records: list = [] if journal is None else list(journal.records)
        self._latest: dict = {} if journal is None else journal.latest()
        self._resumed = journal is not None
        self._remeasure = {int(i) for i in remeasure}
        self._cancel = threading.Event()
        self._running = threading.Event()
        self._running.set()
        self.durations = PatchDurationModel()
        self.planner = planner
        self.decisions: list = []  # this run's decision records (a dynamic plan's), as journaled
        self._decisions_read = () if journal is None else tuple(journal.decisions)

    # -- construction -------------------------------------------------------------------

    @classmethod
    def start(cls, out_dir, plan: MeasurementPlan, display, meter: Meter, *,
              display_name: str | None = None, settings: dict | None = None,
              clock: Callable[[JournalHeader, Journal | None], SessionClock] | None = None,
              **options) -> "MeasurementRun":
        """A new session: identify the instrument and write the journal header.

        Parameters
        ----------
        out_dir : path-like
            Output directory; must not hold a journal yet.
        plan : MeasurementPlan
        display : PatchDisplay
        meter : Meter
        display_name : str, optional
            What showed the patches, for the journal header; ``display.describe()`` by default.
        settings : dict, optional
            Extra settings to keep in the header (effects, time scale, …).
        clock : callable, optional
            ``clock(header, journal)`` returns the session clock; a
            :class:`WallSessionClock` from the header's start by default.
        **options
            ``on_countdown``, ``settle_s``, ``max_consecutive_failures``, ``wall_clock``.
        """
        out_dir = Path(out_dir)
        header = JournalHeader(plan=plan, instrument=_identity(meter),
                               display=display.describe() if display_name is None else display_name,
                               settings=dict(settings or {}))
        writer = JournalWriter.create(out_dir / JOURNAL_NAME, header)
        make_clock = clock or (lambda h, j: WallSessionClock(h.started_epoch_s))
        return cls(out_dir, header, None, writer, display, meter, make_clock(header, None), **options)

    @classmethod
    def resume_session(cls, out_dir, display, meter: Meter, *, plan: MeasurementPlan | None = None,
                       journal: Journal | None = None, resume_details: dict | None = None,
                       clock: Callable[[JournalHeader, Journal | None], SessionClock] | None = None,
                       remeasure=(), add_plan: MeasurementPlan | None = None, **options) -> "MeasurementRun":
        """Continue the session journaled in ``out_dir`` (or add patches to a finished one).

        Parameters
        ----------
        plan : MeasurementPlan, optional
            If given, it must equal the journal's plan (same patches in the
            same order): a resumed run never changes what is measured.
        journal : Journal, optional
            ``out_dir``'s journal if the caller has read it already (it is read
            here otherwise); the file must not have changed since.
        resume_details : dict, optional
            More fields for the journal's resume record (e.g. the noise seed of
            a simulated instrument).
        clock : callable, optional
            As for :meth:`start`.
        remeasure : iterable of int, optional
            Plan indices to measure again even though they were measured; the
            journal keeps the earlier record, the new one supersedes it, and
            the resume record lists them as ``"remeasure"``.
        add_plan : MeasurementPlan, optional
            Patches to add to a **finished** session (``measure --add-plan``,
            a follow-up of :mod:`workbench.diagnostics.follow_up`): the resume
            record carries them (on disk before the first is measured), the
            plan grows by them, and they are measured like pending patches,
            so a crash in the follow-up is continued by a plain resume. The
            patch display must describe itself as the journal's did (the
            same panel through the same runtime).
        **options
            As for :meth:`start`.

        Raises
        ------
        InputError
            If ``plan`` differs from the journal's, or the instrument is
            another one, or ``remeasure`` names an index outside the plan;
            with ``add_plan``: if the session is unfinished, the plan to add
            is empty, or the patch display is another one.
        JournalBusyError
            If another run is writing the journal.
        """
        out_dir = Path(out_dir)
        if journal is None:
            journal = read_journal(out_dir / JOURNAL_NAME)
        if journal.truncated:
            _LOG.warning("%s: ignoring an incomplete last line (the run died while writing it)", journal.path)
        header = journal.header
        if plan is not None and plan.patches != header.plan.patches:
            raise InputError(
                f"{journal.path} was measured with plan {header.plan.name!r} (seed {header.plan.seed}), "
                f"which differs from the plan given now ({plan.name!r}, seed {plan.seed}); "
                "resume without --plan/--plan-file/--seed, or give the same ones as the first run"
            )
        identity = _identity(meter)
        if header.instrument.get("serial") and identity.get("serial") != header.instrument.get("serial"):
            raise InputError(
                f"{journal.path} was measured with instrument serial {header.instrument.get('serial')!r}, "
                f"this one is {identity.get('serial')!r}; resume with the same instrument, or start a new run"
            )
        remeasure = sorted({int(i) for i in remeasure})
        outside = [i for i in remeasure if not 0 <= i < len(header.plan)]
        if outside:
            raise InputError(f"cannot re-measure journal index {outside[0]}: the plan of {journal.path} "
                             f"has indices 0 to {len(header.plan) - 1}")
        details = {**(resume_details or {}), **({"remeasure": remeasure} if remeasure else {})}
        if add_plan is not None:
            _check_addition(journal, add_plan, display)
            details["add_plan"] = added_plan_json(add_plan)
            header = header.with_added(add_plan)
        writer = JournalWriter.append_to(journal, details or None)
        make_clock = clock or (lambda h, j: WallSessionClock(h.started_epoch_s))
        return cls(out_dir, header, journal, writer, display, meter, make_clock(header, journal),
                   remeasure=remeasure, **options)

    # -- control (any thread) -----------------------------------------------------------

    def pause(self) -> None:
        """Pause before the next patch (the patch in flight completes)."""
        self._running.clear()

    def resume(self) -> None:
        """Continue a paused run."""
        self._running.set()

    def cancel(self) -> None:
        """Cancel: the measurement in flight is stopped (``MEAS,0``) and the run ends."""
        self._cancel.set()
        self._running.set()

    @property
    def cancelled(self) -> bool:
        return self._cancel.is_set()

    # -- the run ------------------------------------------------------------------------

    def pending_indices(self) -> list:
        """Plan indices still to measure: no record yet, the latest attempt failed, or asked to re-measure."""
        return [i for i in range(len(self.plan))
                if i not in self._latest or not self._latest[i].ok or i in self._remeasure]

    def _done(self) -> int:
        return sum(1 for r in self._latest.values() if r.ok)

    def _eta(self, pending: list) -> float | None:
        return self.durations.remaining_s([self.plan.patches[i] for i in pending])

    def journal_so_far(self) -> Journal:
        """The journal's header and measurement records so far (earlier runs' and this run's), from memory."""
        return Journal(self._writer.path, self.header, tuple(self._records),
                       decisions=tuple(self._decisions_read) + tuple(self.decisions))

    def events(self) -> Iterator:
        """Perform the run, yielding one event per step; the last is :class:`RunFinished`.

        Raises
        ------
        RunAborted
            The instrument's port vanished, the display failed, or too many
            patches failed in a row; the message names the patch and says to
            resume. The journal is closed intact.
        """
        started = self.wall_clock()
        total = len(self.plan)
        pending = self.pending_indices()
        try:
            yield RunStarted(total, self._done(), self._resumed)
            consecutive_failures = 0
            status = "finished"
            if not pending:
                pending = self._grow_plan()  # a dynamic plan resumed between two decisions
                total = len(self.plan)
            for position, index in enumerate(pending):  # a dynamic plan's list grows as it goes
                if not self._running.is_set() and not self._cancel.is_set():
                    yield RunPaused(self._done(), total, index)
                    while not self._running.wait(_PAUSE_POLL_S):
                        pass
                    if not self._cancel.is_set():
                        yield RunResumed(self._done(), total)
                if self._cancel.is_set():
                    status = "cancelled"
                    break
                patch = self.plan.patches[index]
                yield PatchStarted(index, patch, self._done(), total, self._eta(pending[position:]))
                measured = self._measure_patch(index, patch)
                if measured is None:
                    status = "cancelled"
                    break
                record, wall_s = measured
                record = self._writer.write_record(record)
                if index in self._latest:
                    _LOG.info("%s: the new record supersedes the one measured at t = %.1f s (the journal "
                              "keeps both)", _where(index, patch, total), self._latest[index].t_s)
                self._remeasure.discard(index)
                self._records.append(record)
                self._latest[index] = record
                self.durations.observe(patch, record.Lv, wall_s)
                consecutive_failures = 0 if record.ok else consecutive_failures + 1
                yield PatchMeasured(record, self._done(), total, self._eta(pending[position + 1:]))
                if consecutive_failures >= self.max_consecutive_failures:
                    raise RunAborted(
                        f"{consecutive_failures} patches failed in a row, the last {_where(index, patch, total)}: "
                        f"{record.reason}. The journal in {self.out_dir} keeps every "
                        "measurement; check the instrument, then run again with --resume "
                        "(failed patches are measured again)",
                        index, patch,
                    )
                if position + 1 == len(pending):  # the last pending patch: a dynamic plan decides
                    pending += self._grow_plan()
                    total = len(self.plan)
            outputs = (self._writer.path,)
            if status == "finished":
                outputs += self.export()
            failed = tuple(self.journal_so_far().failed_records())
            summary = RunSummary(status, total, self._done(), failed, self.clock.now(),
                                 self.wall_clock() - started, outputs)
            yield RunFinished(summary)
        finally:
            self._writer.close()

    def _grow_plan(self) -> list:
        """Ask the dynamic plan for its next patches (journaled before they are measured);
        their plan indices, or [] when it has none (or there is no planner)."""
        if self.planner is None or self._cancel.is_set():
            return []
        decision = self.planner.decide(self.journal_so_far())
        if decision is None or not decision.patches:
            return []
        record = self._writer.write_decision(decision.to_json())
        start = len(self.plan)
        self.header = self.header.with_decision(decision.patches)
        self.plan = self.header.plan
        self.decisions.append(record)
        return list(range(start, len(self.plan)))

    def _measure_patch(self, index: int, patch: Patch) -> tuple[JournalRecord, float] | None:
        """Show and measure one patch: the record to journal and the wall seconds it
        took, or ``None`` if cancelled."""
        where = _where(index, patch, len(self.plan))
        resume_hint = (f"The journal in {self.out_dir} keeps every measurement before it; "
                       "fix the cause and run the same command with --resume")
        wall_start = self.wall_clock()
        t_s = self.clock.now()
        try:
            show_patch(self.display, list(patch.rgb), patch.window, list(patch.surround))
        except PatchDisplayError as error:
            raise RunAborted(f"the display failed to show {where}: {error}. {resume_hint}", index, patch) from error
        if self.settle_s > 0:
            self._cancel.wait(self.settle_s)
        try:
            measurement = self.meter.measure(progress=self.on_countdown, cancel=self._cancel)
        except MeasurementCancelled:
            return None
        except PortVanishedError as error:
            raise RunAborted(f"the instrument's port vanished while measuring {where}: {error}. {resume_hint}",
                             index, patch) from error
        except CS2000Error as error:
            _LOG.warning("%s failed: %s", where, error)
            return self._failed(index, patch, t_s, wall_start, str(error))
        except OSError as error:
            raise RunAborted(f"the connection to the instrument failed while measuring {where}: {error}. "
                             f"{resume_hint}", index, patch) from error
        XYZ = _finite_or_none(measurement.XYZ)
        wavelengths = np.asarray(measurement.wavelengths, dtype=float)
        spectrum = np.asarray(measurement.radiance, dtype=float)
        not_computable = ~np.isfinite(spectrum)
        spectrum_problem = (
            f"the instrument could not compute the spectral radiance at {int(not_computable.sum())} of "
            f"{spectrum.size} wavelengths ({_nm_ranges(wavelengths[not_computable])})"
            if not_computable.any() else ""
        )
        if XYZ is None:
            reason = f"the instrument could not compute XYZ (sent {list(measurement.XYZ)})"
            return self._failed(index, patch, t_s, wall_start,
                                f"{reason}, and {spectrum_problem}" if spectrum_problem else reason)
        warning = ""
        if spectrum_problem:
            warning = f"{spectrum_problem}; the spectrum is left out, XYZ, Lv and xy are the instrument's"
            _LOG.warning("%s: %s", where, warning)
        xy = _finite_or_none(measurement.xy)
        record = JournalRecord(
            index=index, kind=patch.kind, rgb=patch.rgb, status="ok", t_s=t_s,
            window=patch.window, surround=tuple(patch.surround),
            duration_s=self.clock.now() - t_s, XYZ=tuple(XYZ),
            Lv=float(measurement.Lv) if math.isfinite(measurement.Lv) else XYZ[1],
            xy=None if xy is None else tuple(xy),
            integration_s=None if measurement.integration_s is None else float(measurement.integration_s),
            nd_used=None if measurement.nd_used is None else bool(measurement.nd_used),
            wavelengths=None if warning else wavelengths,
            spectrum=None if warning else spectrum,
            warning=warning,
            measurement_time_s=_announced_s(measurement),
        )
        return record, self.wall_clock() - wall_start

    def _failed(self, index: int, patch: Patch, t_s: float, wall_start: float, reason: str):
        record = JournalRecord(index=index, kind=patch.kind, rgb=patch.rgb, status="failed", t_s=t_s,
                               window=patch.window, surround=tuple(patch.surround),
                               duration_s=self.clock.now() - t_s, reason=reason)
        return record, self.wall_clock() - wall_start

    def export(self) -> tuple:
        """Write ``session.csv`` and ``session.ti3`` from the journal; returns their paths.

        The journal is taken from memory (:meth:`journal_so_far`), which holds
        each record as written, so the exports equal what the file would give.
        """
        journal = self.journal_so_far()
        session = journal_to_session(journal)
        instrument = " ".join(str(journal.header.instrument.get(k, "")) for k in ("model", "serial")).strip()
        csv_path = write_session_csv(session, self.out_dir / SESSION_CSV_NAME)
        if not np.any(session.mask("white") | np.all(session.rgb >= 255, axis=1)):
            _LOG.warning("no white measured: %s not written (it is normalised to white)", SESSION_TI3_NAME)
            return (csv_path,)
        if session.has_surround_data:  # a .ti3 has no window/surround: it gets the full-field patches
            session = session.subset(session.window_or_full >= 1)
        ti3_path = write_session_ti3(session, self.out_dir / SESSION_TI3_NAME,
                                     instrument=f"Konica Minolta {instrument}".strip())
        return csv_path, ti3_path


def _check_addition(journal: Journal, add_plan: MeasurementPlan, display) -> None:
    """Refuse to add ``add_plan`` to ``journal`` unless the session is finished and shown the same way."""
    directory = journal.path.parent
    if not add_plan.patches:
        raise InputError(f"the plan to add ({add_plan.name}) holds no patches: nothing to measure")
    pending = journal.pending_indices()
    if pending:
        raise InputError(
            f"{journal.path} is not a finished session: {len(pending)} of its {len(journal.header.plan)} "
            f"patches have no successful measurement (the first: journal index {pending[0]}); finish "
            f"it first (measure --resume --out {directory}, or Resume on the Calibrate page), then add "
            "the plan")
    shown_on = display.describe()
    if journal.header.display and shown_on != journal.header.display:
        raise InputError(
            f"{journal.path} was measured on {journal.header.display!r}, and the patches would now be "
            f"shown on {shown_on!r}: a follow-up must be shown the way the session was (the same panel "
            "through the same runtime), or its rows do not belong in the session; use the session's "
            "--display (and --effect), or measure the plan as a new session with --plan-file")


def _announced_s(measurement) -> float | None:
    """The measurement time the instrument announced (``OK00,ttt``), where the meter reports it."""
    value = getattr(measurement, "measurement_time_s", None)
    return None if value is None or not math.isfinite(float(value)) else float(value)


def _identity(meter: Meter) -> dict:
    """The instrument's identity as a JSON-able dict."""
    identity = meter.identify()
    return {key: str(getattr(identity, key, "")) for key in ("name", "model", "serial")}
