"""The measurement journal: a crash-safe, append-only record of a session (design §4).

A journal is a text file of JSON lines (``journal.jsonl``):

1. a **header** record, written when the session starts::

       {"record": "header", "format": "vr-workbench-journal/1", "software": "vr-colour-workbench 0.1.0",
        "started_utc": "2025-01-01T12:00:00+00:00", "started_epoch_s": 1735732800.0,
        "plan": {"name": "paper", "seed": 7, "patches": [["black", 0, 0, 0], ...]},
        "instrument": {"name": "CS-2000", "model": "CS-2000", "serial": "12345"},
        "display": "simulated OLED HMD (...)", "settings": {..., "eye": "both", "sync": "internal:90"}}

   ``settings`` holds, besides a simulation's effects and seed, which panel
   showed the patches (``eye``: ``both``, ``left`` or ``right``) and the
   instrument's sync mode (``sync``: ``none``, ``internal:HZ``, ``external``),
   for journals written since they are recorded (:attr:`JournalHeader.eye`,
   :attr:`JournalHeader.sync`); the session's metadata carries them on;

2. one **measurement** record per patch, appended, flushed and ``fsync``-ed
   before the next patch is shown::

       {"record": "measurement", "index": 0, "kind": "black", "rgb": [0, 0, 0], "status": "ok",
        "t_s": 0.0, "duration_s": 12.3, "XYZ": [..], "Lv": .., "xy": [..], "integration_s": ..,
        "nd_used": false, "spectrum": {"start_nm": 380, "step_nm": 1, "values": [...]}}

   or, for a patch that failed after the instrument's own recovery,
   ``"status": "failed", "reason": "CS-2000 ER10: ..."`` and no values. An
   ``ok`` record may carry a ``"warning"`` (e.g. the instrument could not
   compute the spectrum, which is then left out, while its XYZ are kept);

3. a **resume** record each time ``--resume`` picks the session up again
   (with whatever the resuming run adds, e.g. a simulation's noise seed).
   A resume record that carries ``"add_plan": {"name": ..., "patches": [...]}``
   (``measure --add-plan``: a follow-up measured into a finished session)
   makes the plan grow by those patches, numbered on from the last index;
   :attr:`Journal.header` is then the header with the grown plan (the file's
   header line is never rewritten), so a ``--resume`` after a crash in the
   follow-up measures what is left of it like any other pending patch.

4. a **decision** record each time a dynamic plan (``measure --plan adaptive``,
   :mod:`workbench.measurement.adaptive`) chooses what to measure next::

       {"record": "decision", "number": 3, "patches": [["ramp-b", 0, 0, 60]],
        "reason": "blue tone curve between DAC 32 and 64: ...", ...}

   written (fsynced) before its patches are measured; like an ``add_plan``
   the plan grows by its patches (numbered on from the last index, the plan
   keeps its name), so a resumed run measures what a decision added and the
   planner, reading the same measurements, goes on from the same state.
   :attr:`Journal.decisions` holds them in file order.

Nothing is ever rewritten in place. A crash can leave a truncated last line;
:func:`read_journal` ignores it (and reports that it did), and
:meth:`JournalWriter.append_to` cuts it off before appending. ``index`` is the
patch's position in the plan; a patch whose latest record is ``failed`` is
measured again on resume, and its later record supersedes the earlier one.

One writer at a time: :class:`JournalWriter` holds an exclusive ``flock`` on
the journal for as long as it is open (POSIX), so a second ``measure`` run on
the same directory stops with :class:`JournalBusyError` instead of measuring
the pending patches a second time.

Units as in :mod:`workbench`: XYZ and ``Lv`` absolute (cd/m²), spectral
radiance in W·sr⁻¹·m⁻²·nm⁻¹, ``t_s`` seconds since the session began (the
instrument's modelled time for simulated sessions), DAC values 0..255.
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from workbench import __version__
from workbench.errors import SpectrumFileError, WorkbenchError
from workbench.measurement.plans import MeasurementPlan, Patch
from workbench.session import Session

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: no advisory lock, one writer is up to the user
    fcntl = None

__all__ = [
    "JOURNAL_FORMAT",
    "SOFTWARE",
    "JournalHeader",
    "JournalRecord",
    "Journal",
    "JournalWriter",
    "JournalBusyError",
    "read_journal",
    "journal_to_session",
    "added_plan_json",
]

JOURNAL_FORMAT = "vr-workbench-journal/1"
"""Format tag of the header record."""

SOFTWARE = f"vr-colour-workbench {__version__}"
"""Software name and version written into every header and resume record."""

_LOG = logging.getLogger(__name__)


class JournalBusyError(WorkbenchError):
    """Another process is writing the journal (or wrote to it while this one started)."""


def _patch_entry(patch: Patch) -> list:
    """A patch as the journal writes it: ``[kind, r, g, b]``, or ``[kind, r, g, b, window, sr, sg, sb]``."""
    return [patch.kind, *patch.rgb, patch.window, *patch.surround] if patch.is_apl else [patch.kind, *patch.rgb]


def _patch_of(entry) -> Patch:
    """The patch of a journal entry (:func:`_patch_entry`)."""
    return Patch(str(entry[0]), tuple(int(v) for v in entry[1:4]),
                 *((float(entry[4]), tuple(int(v) for v in entry[5:8])) if len(entry) == 8 else ()))


def added_plan_json(plan: MeasurementPlan) -> dict:
    """The ``add_plan`` field of a resume record that adds ``plan``'s patches to a session."""
    return {"name": plan.name, "patches": [_patch_entry(p) for p in plan.patches]}


def _utc_iso(epoch_s: float) -> str:
    return _dt.datetime.fromtimestamp(epoch_s, _dt.timezone.utc).isoformat(timespec="seconds")


@dataclass(frozen=True)
class JournalHeader:
    """The first record of a journal: what is measured, with what, by what.

    Attributes
    ----------
    plan : MeasurementPlan
        The full plan, so that a resumed session shows exactly the same patches.
    instrument : dict
        Identity of the instrument (name, model, serial).
    display : str
        What showed the patches.
    settings : dict
        Anything else worth keeping (simulated effects, time scale, …).
    software : str
        Name and version of the software that started the session.
    started_epoch_s : float
        Start time in seconds since the Unix epoch (now, by default).
    """

    plan: MeasurementPlan
    instrument: dict
    display: str
    settings: dict = field(default_factory=dict)
    software: str = SOFTWARE
    started_epoch_s: float = field(default_factory=time.time)

    @property
    def started_utc(self) -> str:
        """Start time, ISO 8601 in UTC."""
        return _utc_iso(self.started_epoch_s)

    @property
    def eye(self) -> str | None:
        """Which panel showed the patches (``both``, ``left``, ``right``; ``measure --eye``), from
        ``settings``; ``None`` for a journal written before it was recorded."""
        return self.settings.get("eye")

    @property
    def sync(self) -> str | None:
        """The CS-2000's sync mode during the session (``none``, ``internal:HZ``, ``external``;
        ``measure --sync``), from ``settings``; ``None`` for a journal written before it was recorded."""
        return self.settings.get("sync")

    def to_json(self) -> dict:
        return {
            "record": "header",
            "format": JOURNAL_FORMAT,
            "software": self.software,
            "started_utc": self.started_utc,
            "started_epoch_s": self.started_epoch_s,
            "plan": {
                "name": self.plan.name,
                "seed": self.plan.seed,
                "patches": [_patch_entry(p) for p in self.plan.patches],
            },
            "instrument": self.instrument,
            "display": self.display,
            "settings": self.settings,
        }

    def with_added(self, added: MeasurementPlan) -> "JournalHeader":
        """This header with ``added``'s patches appended to its plan (``measure --add-plan``).

        The plan keeps its seed; its name becomes ``"<plan> + <added file name>"``.
        """
        name = f"{self.plan.name} + {Path(added.name).name}"
        return replace(self, plan=MeasurementPlan(name, self.plan.patches + tuple(added.patches),
                                                  self.plan.seed))

    def with_decision(self, patches) -> "JournalHeader":
        """This header with a dynamic plan's decided ``patches`` appended (the plan keeps its name)."""
        return replace(self, plan=MeasurementPlan(self.plan.name, self.plan.patches + tuple(patches),
                                                  self.plan.seed))

    @classmethod
    def from_json(cls, data: dict) -> "JournalHeader":
        plan = data["plan"]
        patches = tuple(_patch_of(entry) for entry in plan["patches"])
        return cls(
            plan=MeasurementPlan(str(plan["name"]), patches, plan.get("seed")),
            instrument=dict(data.get("instrument") or {}),
            display=str(data.get("display", "")),
            settings=dict(data.get("settings") or {}),
            software=str(data.get("software", "")),
            started_epoch_s=float(data.get("started_epoch_s", 0.0)),
        )


@dataclass(frozen=True)
class JournalRecord:
    """One measurement (or one failed attempt) of one patch.

    Attributes
    ----------
    index : int
        Position of the patch in the plan.
    kind : str
    rgb : (int, int, int)
    status : str
        ``"ok"`` or ``"failed"``.
    t_s : float
        Session-clock time at which the patch was shown, seconds.
    duration_s : float
        Session-clock time the patch took (show + measure), seconds.
    XYZ : (float, float, float) or None
        Absolute tristimulus values (cd/m²); ``None`` when failed.
    Lv : float or None
        Luminance, cd/m².
    xy : (float, float) or None
        CIE 1931 chromaticity (``None`` also when not computable, e.g. black).
    integration_s : float or None
        The instrument's integration time.
    nd_used : bool or None
        Whether the instrument's internal ND filter was in.
    wavelengths : ndarray or None
        Wavelengths (nm) of ``spectrum``.
    spectrum : ndarray or None
        Spectral radiance, W·sr⁻¹·m⁻²·nm⁻¹.
    reason : str
        Why the patch failed (empty when ok).
    warning : str
        What is missing from an ``ok`` record and why (empty when nothing is),
        e.g. a spectrum the instrument could not compute.
    window : float
        Fraction of the field the patch covered (1: full field).
    surround : (int, int, int)
        DAC values of the rest of the field.
    measurement_time_s : float or None
        The measurement time the instrument announced (the CS-2000's
        ``OK00,ttt`` reply to ``MEAS,1``), where the meter reports one.
    """

    index: int
    kind: str
    rgb: tuple
    status: str
    t_s: float
    duration_s: float
    XYZ: tuple | None = None
    Lv: float | None = None
    xy: tuple | None = None
    integration_s: float | None = None
    nd_used: bool | None = None
    wavelengths: np.ndarray | None = field(default=None, compare=False)
    spectrum: np.ndarray | None = field(default=None, compare=False)
    reason: str = ""
    warning: str = ""
    window: float = 1.0
    surround: tuple = (0, 0, 0)
    measurement_time_s: float | None = None

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def patch(self) -> Patch:
        return Patch(self.kind, tuple(self.rgb), self.window, tuple(self.surround))

    def to_json(self) -> dict:
        data = {
            "record": "measurement",
            "index": self.index,
            "kind": self.kind,
            "rgb": list(self.rgb),
            "status": self.status,
            "t_s": round(self.t_s, 6),
            "duration_s": round(self.duration_s, 6),
        }
        if self.window < 1.0:  # an APL patch: a window on a surround
            data.update(window=self.window, surround=list(self.surround))
        if self.ok:
            data.update(
                XYZ=list(self.XYZ),
                Lv=self.Lv,
                xy=None if self.xy is None else list(self.xy),
                integration_s=self.integration_s,
                nd_used=self.nd_used,
            )
            if self.spectrum is not None:
                step = float(np.median(np.diff(self.wavelengths))) if len(self.wavelengths) > 1 else 1.0
                data["spectrum"] = {
                    "start_nm": float(self.wavelengths[0]),
                    "step_nm": step,
                    "values": [float(f"{v:.7g}") for v in self.spectrum],
                }
            if self.warning:
                data["warning"] = self.warning
            if self.measurement_time_s is not None:  # the seconds MEAS,1 announced (OK00,ttt)
                data["measurement_time_s"] = self.measurement_time_s
        else:
            data["reason"] = self.reason
        return data

    @classmethod
    def from_json(cls, data: dict) -> "JournalRecord":
        spectrum = data.get("spectrum")
        wavelengths = values = None
        if spectrum:
            values = np.asarray(spectrum["values"], dtype=float)
            wavelengths = spectrum["start_nm"] + spectrum["step_nm"] * np.arange(len(values))
        return cls(
            index=int(data["index"]),
            kind=str(data["kind"]),
            rgb=tuple(int(v) for v in data["rgb"]),
            status=str(data["status"]),
            t_s=float(data["t_s"]),
            duration_s=float(data.get("duration_s", 0.0)),
            XYZ=None if data.get("XYZ") is None else tuple(float(v) for v in data["XYZ"]),
            Lv=None if data.get("Lv") is None else float(data["Lv"]),
            xy=None if data.get("xy") is None else tuple(float(v) for v in data["xy"]),
            integration_s=data.get("integration_s"),
            nd_used=data.get("nd_used"),
            wavelengths=wavelengths,
            spectrum=values,
            reason=str(data.get("reason", "")),
            warning=str(data.get("warning", "")),
            window=float(data.get("window", 1.0)),
            surround=tuple(int(v) for v in data.get("surround", (0, 0, 0))),
            measurement_time_s=(None if data.get("measurement_time_s") is None
                                else float(data["measurement_time_s"])),
        )


@dataclass(frozen=True)
class Journal:
    """A journal as read back.

    Attributes
    ----------
    path : Path
    header : JournalHeader
    records : tuple of JournalRecord
        Every measurement record, in file order (failed attempts included).
    resumes : tuple of dict
        The resume records.
    truncated : bool
        Whether an incomplete last line (a crash mid-write) was ignored.
    complete_bytes : int
        Length of the file up to the end of its last complete line.
    size_bytes : int or None
        Length of the file when it was read (``None`` for a journal put
        together in memory); :meth:`JournalWriter.append_to` refuses a file
        that has changed since.
    decisions : tuple of dict
        The decision records of a dynamic plan, in file order (their patches
        are in the header's plan already).
    """

    path: Path
    header: JournalHeader
    records: tuple
    resumes: tuple = ()
    truncated: bool = False
    complete_bytes: int = 0
    size_bytes: int | None = None
    decisions: tuple = ()

    def latest(self) -> dict:
        """The latest record of each plan index that has one: ``{index: JournalRecord}``."""
        return {record.index: record for record in self.records}

    def ok_records(self) -> list:
        """The successful measurements, in plan order."""
        return [r for _, r in sorted(self.latest().items()) if r.ok]

    def failed_records(self) -> list:
        """Patches whose latest attempt failed, in plan order."""
        return [r for _, r in sorted(self.latest().items()) if not r.ok]

    def superseded_records(self) -> list:
        """Records a later record of the same patch replaced (failed attempts, re-measurements), in file order."""
        latest = self.latest()
        return [r for r in self.records if latest[r.index] is not r]

    def pending_indices(self) -> list:
        """Plan indices without a successful measurement (never measured, or the latest attempt failed)."""
        latest = self.latest()
        return [i for i in range(len(self.header.plan)) if i not in latest or not latest[i].ok]

    @property
    def additions(self) -> tuple:
        """The resume records that added patches to the plan (``measure --add-plan``), in file order."""
        return tuple(r for r in self.resumes if r.get("add_plan"))

    def session_end_s(self) -> float:
        """Session time at which the last journaled patch ended (0 for none)."""
        return max((r.t_s + r.duration_s for r in self.records), default=0.0)


def read_journal(path: str | os.PathLike) -> Journal:
    """Read a journal, ignoring a truncated last line.

    Raises
    ------
    SpectrumFileError
        If the file is missing, has no header, or a complete line (not the
        last) is not a valid record; the message names the line and the fix.
    """
    path = Path(path)
    if not path.is_file():
        raise SpectrumFileError(path, None, "no such journal", "give the directory of an earlier run (DIR/journal.jsonl)")
    data = path.read_bytes()
    lines = data.split(b"\n")
    tail = lines.pop()  # bytes after the last newline: empty, or a line cut short by a crash
    truncated = bool(tail.strip())
    complete_bytes = len(data) - len(tail)
    header, records, resumes, decisions = None, [], [], []
    for number, raw in enumerate(lines, start=1):
        if not raw.strip():
            continue
        try:
            entry = json.loads(raw)
            kind = entry["record"]
            if kind == "header":
                if header is not None:
                    raise ValueError("a second header")
                if entry.get("format") != JOURNAL_FORMAT:
                    raise ValueError(f"format {entry.get('format')!r}, not {JOURNAL_FORMAT!r}")
                header = JournalHeader.from_json(entry)
            elif header is None:
                raise ValueError("a record before the header")
            elif kind == "measurement":
                record = JournalRecord.from_json(entry)
                if not 0 <= record.index < len(header.plan):
                    raise ValueError(f"patch index {record.index} outside the plan's {len(header.plan)} patches")
                records.append(record)
            elif kind == "resume":
                if entry.get("add_plan"):
                    added = entry["add_plan"]
                    patches = tuple(_patch_of(p) for p in added["patches"])
                    header = header.with_added(MeasurementPlan(str(added.get("name", "added plan")),
                                                               patches, None))
                resumes.append(entry)
            elif kind == "decision":
                header = header.with_decision(tuple(_patch_of(p) for p in entry.get("patches", ())))
                decisions.append(entry)
            else:
                raise ValueError(f"unknown record type {kind!r}")
        except (ValueError, KeyError, TypeError) as error:
            raise SpectrumFileError(
                path, number, f"not a valid journal record ({error})",
                "journals are written by `vr-workbench measure`; restore the file from a backup or start a new run",
            ) from None
    if header is None:
        raise SpectrumFileError(path, 1, "no header record",
                                "the run died before it started; delete the directory and start again")
    return Journal(path, header, tuple(records), tuple(resumes), truncated, complete_bytes, len(data),
                   tuple(decisions))


class JournalWriter:
    """Appends records to a journal, each flushed and fsynced before returning.

    Use :meth:`create` for a new session and :meth:`append_to` to resume one.
    While it is open the writer holds an exclusive, non-blocking ``flock`` on
    the journal (released by :meth:`close`, or by the process ending, however
    it ends): a second writer is refused with :class:`JournalBusyError`.
    """

    def __init__(self, path: Path, handle):
        self.path = path
        self._handle = handle

    @classmethod
    def create(cls, path: str | os.PathLike, header: JournalHeader) -> "JournalWriter":
        """Start a new journal at ``path`` (which must not exist) with ``header``.

        Raises
        ------
        JournalBusyError
            If another run is writing the journal at ``path``.
        SpectrumFileError
            If a journal already exists there (``--resume`` continues it).
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            handle = open(path, "xb")
        except FileExistsError:
            if _is_locked(path):
                raise _busy(path) from None
            raise SpectrumFileError(
                path, None, "a journal already exists here",
                "add --resume to continue that run, or choose another --out directory",
            ) from None
        _lock(handle, path)
        writer = cls(path, handle)
        writer._write(header.to_json())
        _fsync_directory(path.parent)
        return writer

    @classmethod
    def append_to(cls, journal: Journal, resume_details: dict | None = None) -> "JournalWriter":
        """Continue ``journal``: cut off a truncated last line, then append a resume record.

        Parameters
        ----------
        journal : Journal
            As :func:`read_journal` returned it; the file must not have changed since.
        resume_details : dict, optional
            More fields for the resume record (JSON-able), e.g. a simulation's
            noise seed, or ``add_plan`` (:func:`added_plan_json`): patches the
            session's plan grows by (the record is on disk, fsynced, before
            the first of them is measured).

        Raises
        ------
        JournalBusyError
            If another run is writing the journal, or wrote to it after it was read.
        """
        handle = open(journal.path, "r+b")
        _lock(handle, journal.path)
        size = os.fstat(handle.fileno()).st_size
        if journal.size_bytes is not None and size != journal.size_bytes:
            handle.close()
            raise JournalBusyError(
                f"{journal.path} changed while this run was starting ({journal.size_bytes} bytes when "
                f"read, {size} now): another measure run wrote to it; wait for it or stop it, then "
                "run again with --resume"
            )
        handle.truncate(journal.complete_bytes)
        handle.seek(journal.complete_bytes)
        writer = cls(journal.path, handle)
        writer._write({"record": "resume", "software": SOFTWARE, "time_utc": _utc_iso(time.time()),
                       "measured_before": len(journal.records), **(resume_details or {})})
        return writer

    def _write(self, entry: dict) -> None:
        line = json.dumps(entry, separators=(",", ":"), allow_nan=False).encode("utf-8") + b"\n"
        self._handle.write(line)
        self._handle.flush()
        os.fsync(self._handle.fileno())

    def write_record(self, record: JournalRecord) -> JournalRecord:
        """Append one measurement record; on return it is on disk.

        Returns
        -------
        JournalRecord
            The record as the journal holds it (and :func:`read_journal` will
            read it back): values rounded as written.
        """
        entry = record.to_json()
        self._write(entry)
        return JournalRecord.from_json(entry)

    def write_decision(self, entry: dict) -> dict:
        """Append a dynamic plan's decision record (``entry`` JSON-able, with ``patches``); on
        return it is on disk. Returns the record as written."""
        record = {"record": "decision", **entry}
        self._write(record)
        return record

    def close(self) -> None:
        """Close the file, which releases the lock."""
        if not self._handle.closed:
            self._handle.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _busy(path: Path) -> JournalBusyError:
    return JournalBusyError(f"another measure run is writing {path}; wait for it or stop it")


def _lock(handle, path: Path) -> None:
    """Take the writer's exclusive lock on ``handle`` without waiting (closes it if refused)."""
    if fcntl is None:
        return
    try:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.close()
        raise _busy(path) from None
    except OSError as error:  # e.g. a file system without flock: carry on, unguarded
        _LOG.warning("%s: cannot lock the journal (%s); make sure no other run writes to it", path, error)


def _is_locked(path: Path) -> bool:
    """Whether a writer holds the lock on ``path`` now."""
    if fcntl is None:
        return False
    try:
        with open(path, "rb") as handle:
            fcntl.flock(handle.fileno(), fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    except OSError:
        return False
    return False


def _fsync_directory(directory: Path) -> None:
    """Make a new file's directory entry durable (POSIX; a no-op where unsupported)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def journal_to_session(journal: Journal) -> Session:
    """The successful measurements of ``journal`` as a :class:`~workbench.session.Session`.

    Rows are in plan order; failed patches are left out. Spectra are included
    when every successful record has one on the same wavelengths (a session
    CSV has no way to leave one row's spectrum blank); otherwise a warning
    names the records without one.
    """
    records = journal.ok_records()
    if not records:
        raise SpectrumFileError(journal.path, None, "the journal holds no successful measurement",
                                "run (or resume) the measurement first")
    spectra = wavelengths = None
    without = [r.index for r in records if r.spectrum is None]
    if without and len(without) < len(records):
        _LOG.warning("%s: %d measurement(s) have no spectrum (journal index %s), so the session has no "
                     "spectral columns; re-measure those patches to get them", journal.path, len(without),
                     ", ".join(map(str, without[:10])) + (", ..." if len(without) > 10 else ""))
    if not without:
        wavelengths = records[0].wavelengths
        if all(len(r.wavelengths) == len(wavelengths) and np.allclose(r.wavelengths, wavelengths) for r in records):
            spectra = np.array([r.spectrum for r in records])
        else:
            wavelengths = None
    apl = any(r.window < 1.0 for r in records)  # window/surround columns only where a patch needs them
    return Session(
        kind=np.array([r.kind for r in records], dtype=object),
        rgb=np.array([r.rgb for r in records], dtype=float),
        XYZ=np.array([r.XYZ for r in records], dtype=float),
        t_s=np.array([r.t_s for r in records], dtype=float),
        wavelengths=wavelengths,
        spectra=spectra,
        source=str(journal.path),
        metadata={"plan": journal.header.plan.name, "instrument": journal.header.instrument,
                  "display": journal.header.display, "software": journal.header.software,
                  **{key: value for key in ("eye", "sync") if (value := getattr(journal.header, key))}},
        window=np.array([r.window for r in records]) if apl else None,
        surround=np.array([r.surround for r in records], dtype=float) if apl else None,
    )
