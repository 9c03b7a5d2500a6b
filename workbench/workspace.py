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
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable
from pathlib import Path

from workbench.errors import WorkbenchError

__all__ = ["EVENTS", "DEFAULT_SOURCES", "Workspace"]

EVENTS = ("session-changed", "diagnosis-changed", "profile-changed", "sources-changed")
"""Every event a :class:`Workspace` emits."""

DEFAULT_SOURCES = ("cie-d65", "d65-two-peak")
"""Sources selected in a new workspace: the paper's reference and its metamer."""


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
