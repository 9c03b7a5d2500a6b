"""The state a user works on, as a Qt-free model that emits events (house style: napari).

A :class:`Workspace` holds the open session, its diagnosis, the current
profile and the selected light sources. Views subscribe to it; a script or a
test drives it without a window. It imports no Qt: :mod:`workbench.gui`
wraps it, never the other way round.

Events (the names are stable; a callback receives the workspace):

``session-changed``
    :attr:`Workspace.session` / :attr:`Workspace.session_path` changed.
``diagnosis-changed``
    :attr:`Workspace.diagnosis` changed (a :class:`workbench.diagnostics.Diagnosis` or None).
``profile-changed``
    :attr:`Workspace.profile` / :attr:`Workspace.profile_path` changed.
``sources-changed``
    :attr:`Workspace.selected_sources` changed (illuminant library ids).
``measurement-changed``
    :attr:`Workspace.measurement` changed (a :class:`MeasurementState`: what
    the running calibration measures, with what, and how far it got).

Opening a file is two steps so that a window can do the slow one in a worker
thread: :func:`load_path` reads and diagnoses (no state, any thread), then
:meth:`Workspace.apply` sets the state and emits (the thread the views live
in). :meth:`Workspace.open_path` does both.
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from workbench.errors import WorkbenchError

__all__ = ["EVENTS", "DEFAULT_SOURCES", "MEASUREMENT_STATUSES", "LoadedPath", "MeasurementState",
           "Workspace", "load_path", "is_profile_file", "unfinished_journal", "measurement_directory",
           "write_follow_up_plan"]

EVENTS = ("session-changed", "diagnosis-changed", "profile-changed", "sources-changed",
          "measurement-changed")
"""Every event a :class:`Workspace` emits."""

DEFAULT_SOURCES = ("cie-d65", "d65-two-peak")
"""Sources selected in a new workspace: the paper's reference and its metamer."""


MEASUREMENT_STATUSES = ("idle", "running", "paused", "finished", "cancelled", "aborted")
"""What :attr:`MeasurementState.status` may be."""


@dataclass(frozen=True)
class MeasurementState:
    """The calibration the workspace runs, as the status bar and the pages show it.

    Attributes
    ----------
    status : str
        One of :data:`MEASUREMENT_STATUSES`.
    instrument : str
        The instrument in use (e.g. ``"simulated CS-2000"``, ``"CS-2000 on /dev/ttyACM0"``).
    display : str
        The patch display in use.
    out_dir : Path or None
        Where the journal and the session files are written.
    done, total : int
        Patches measured so far, and in the plan.
    message : str
        Why the run stopped, for ``aborted``; empty otherwise.
    """

    status: str = "idle"
    instrument: str = ""
    display: str = ""
    out_dir: Path | None = None
    done: int = 0
    total: int = 0
    message: str = ""

    def __post_init__(self):
        if self.status not in MEASUREMENT_STATUSES:
            raise WorkbenchError(f"unknown measurement status {self.status!r}; known: "
                                 f"{', '.join(MEASUREMENT_STATUSES)}")


@dataclass(frozen=True, eq=False)
class LoadedPath:
    """What :func:`load_path` read: a session and its diagnosis, and a profile if the file is one.

    Attributes
    ----------
    path : Path
    session : Session
    diagnosis : Diagnosis
    profile : Profile or None
        The file's profile when ``path`` is a ``.vrprofile.json``; otherwise
        the diagnosis's model as a profile (what ``diagnose --export`` would
        write), not yet saved.
    profile_path : Path or None
        Where ``profile`` is stored: ``path`` for a profile file, None for an
        unsaved one.
    """

    path: Path
    session: object
    diagnosis: object
    profile: object = None
    profile_path: Path | None = None


def is_profile_file(path: str | Path) -> bool:
    """Whether ``path`` is a JSON file whose ``format`` says it is a workbench profile."""
    from workbench.profile import PROFILE_FORMAT

    path = Path(path)
    if not (path.is_file() and path.suffix.lower() == ".json"):
        return False
    try:
        return json.loads(path.read_text(encoding="utf-8")).get("format") == PROFILE_FORMAT
    except (OSError, ValueError, AttributeError):
        return False


def load_path(path: str | Path) -> LoadedPath:
    """Read anything ``diagnose`` reads and diagnose it (no workspace state is touched).

    Parameters
    ----------
    path : path-like
        A session CSV, an Argyll ``.ti3``, a Psychtoolbox ``.mat``, a
        measurement directory (its ``session.csv``) or a ``.vrprofile.json``
        (diagnosed from its primaries, and loaded as the profile too).

    Raises
    ------
    WorkbenchError
        If the file cannot be read or diagnosed; the message names it and the fix.
    """
    from workbench.diagnostics import diagnose
    from workbench.profile import load_profile, profile_from_diagnosis
    from workbench.session_readers import read_session

    path = Path(path)
    if not path.exists():
        raise WorkbenchError(f"{path}: no such file or directory; choose a session CSV, .ti3, .mat, "
                             "a measurement directory or a .vrprofile.json")
    session = read_session(path)
    diagnosis = diagnose(session)
    if is_profile_file(path):
        return LoadedPath(path, session, diagnosis, load_profile(path), path)
    # the headset just measured becomes the current profile (unsaved until exported), so
    # the gamut, the light colours and the scene show this display, not the previous one
    return LoadedPath(path, session, diagnosis, profile_from_diagnosis(diagnosis), None)


def unfinished_journal(directory: str | Path):
    """The journal in ``directory`` if its session was left unfinished (patches to measure), else ``None``.

    A killed or cancelled calibration leaves a journal with patches that have
    no successful record; the window offers to resume it.
    """
    from workbench.measurement.journal import read_journal
    from workbench.measurement.runner import JOURNAL_NAME

    path = Path(directory) / JOURNAL_NAME
    if not path.is_file():
        return None
    journal = read_journal(path)
    ok = {i for i, r in journal.latest().items() if r.ok}
    return journal if len(ok) < len(journal.header.plan) else None


def measurement_directory(path: str | Path | None) -> Path | None:
    """The measurement directory (the one holding the journal) that ``path`` was read from, or None.

    ``path`` is what was opened: a measurement directory, or its ``session.csv``
    or ``session.ti3``. A follow-up can be measured into such a directory
    (``measure --add-plan``); any other file has none.
    """
    from workbench.measurement.runner import JOURNAL_NAME, SESSION_CSV_NAME, SESSION_TI3_NAME

    if path is None:
        return None
    path = Path(path)
    directory = path if path.is_dir() else (path.parent if path.name in (SESSION_CSV_NAME, SESSION_TI3_NAME)
                                            else None)
    return directory if directory is not None and (directory / JOURNAL_NAME).is_file() else None


def write_follow_up_plan(follow_up, session_path: str | Path | None) -> tuple[Path, Path | None]:
    """Write ``follow_up`` (:class:`~workbench.diagnostics.follow_up.FollowUp`) as a plan file.

    Returns ``(plan file, measurement directory)``: in the session's
    measurement directory as ``follow-up-N.csv`` (the first N free) where the
    session has one (it is then measured into it); otherwise in the temporary
    directory (never beside a data file that is not ours), with None.
    """
    import tempfile

    directory = measurement_directory(session_path)
    if directory is None:
        stem = Path(session_path).stem if session_path else "session"
        return follow_up.write(Path(tempfile.gettempdir()) / f"vr-workbench-follow-up-{stem}.csv"), None
    number = 1
    while (directory / f"follow-up-{number}.csv").exists():
        number += 1
    return follow_up.write(directory / f"follow-up-{number}.csv"), directory


class Workspace:
    """The open session, its diagnosis, the current profile and the selected sources.

    A new workspace has no session and, as its profile, the paper's HTC Vive
    (``profiles/htc-vive-paper.vrprofile.json``), so every page has something
    to show before a calibration.
    """

    def __init__(self) -> None:
        from workbench.profile import paper_vive_profile

        self._listeners: dict[str, list[Callable[["Workspace"], None]]] = defaultdict(list)
        self.session = None
        self.session_path: Path | None = None
        self.diagnosis = None
        self.profile = paper_vive_profile()
        self.profile_path: Path | None = None
        self.selected_sources: tuple[str, ...] = DEFAULT_SOURCES
        self.measurement = MeasurementState()

    # -- events -------------------------------------------------------------
    def subscribe(self, event: str, callback: Callable[["Workspace"], None]) -> Callable[[], None]:
        """Call ``callback(workspace)`` on ``event``; returns a function that unsubscribes."""
        if event not in EVENTS:
            raise WorkbenchError(f"unknown workspace event {event!r}; known: {', '.join(EVENTS)}")
        self._listeners[event].append(callback)
        return lambda: self._listeners[event].remove(callback)

    def emit(self, event: str) -> None:
        if event not in EVENTS:
            raise WorkbenchError(f"unknown workspace event {event!r}; known: {', '.join(EVENTS)}")
        for callback in list(self._listeners[event]):
            callback(self)

    # -- state ----------------------------------------------------------------
    def set_session(self, session, path: str | Path | None = None) -> None:
        self.session = session
        self.session_path = Path(path) if path is not None else None
        self.emit("session-changed")

    def set_diagnosis(self, diagnosis) -> None:
        self.diagnosis = diagnosis
        self.emit("diagnosis-changed")

    def set_profile(self, profile, path: str | Path | None = None) -> None:
        self.profile = profile
        self.profile_path = Path(path) if path is not None else None
        self.emit("profile-changed")

    def set_selected_sources(self, source_ids) -> None:
        ids = tuple(dict.fromkeys(str(s) for s in source_ids))
        if not ids:
            raise WorkbenchError("select at least one light source")
        self.selected_sources = ids
        self.emit("sources-changed")

    def set_measurement(self, state: MeasurementState | None = None, **changes) -> None:
        """Replace the measurement state, or change some of its fields (``status=...``)."""
        self.measurement = replace(state or self.measurement, **changes)
        self.emit("measurement-changed")

    # -- files ----------------------------------------------------------------
    def apply(self, loaded: LoadedPath) -> None:
        """Make what :func:`load_path` read the workspace's session, diagnosis (and profile)."""
        self.set_session(loaded.session, loaded.path)
        self.set_diagnosis(loaded.diagnosis)
        if loaded.profile is not None:
            self.set_profile(loaded.profile, loaded.profile_path)

    def open_path(self, path: str | Path) -> LoadedPath:
        """Read, diagnose and apply ``path`` (see :func:`load_path`); returns what was read."""
        loaded = load_path(path)
        self.apply(loaded)
        return loaded

    def export_profile(self, path: str | Path) -> Path:
        """Write the diagnosis's profile to ``path`` (validated before writing), then make it current.

        The extended model is written (the baseline's when nothing was found),
        with its held-out validation figures, the findings and the paper's
        lights, exactly as ``diagnose SESSION --export PROFILE`` writes it.

        Raises
        ------
        WorkbenchError
            If there is no diagnosis yet, or the profile does not validate.
        """
        from workbench.profile import load_profile, profile_from_diagnosis, save_profile

        if self.diagnosis is None:
            raise WorkbenchError("nothing to export: calibrate, or open a session (File ▸ Open), first")
        written = save_profile(profile_from_diagnosis(self.diagnosis), path)
        self.set_profile(load_profile(written), written)
        return Path(written)
