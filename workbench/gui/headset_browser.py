"""The window's one WebXR server: the headset's browser shows the calibration patches and the lightbooth.

:class:`HeadsetBrowser` owns the :class:`~workbench.vr.server.WebXRServer` that
the Calibrate page (patch display "headset browser (WebXR)") and the Scene page
("Show in headset browser") share: one URL, one page in the headset, and the
page's state handed from the server's thread to the GUI thread by a queued
signal (:attr:`HeadsetBrowser.status_changed`). The main window makes it and
closes the server when it closes.

:func:`make_scene_bundle` writes the runtime bundle the page's lightbooth reads
(the workspace's profile, its sources, the lightbooth cube), as ``vr bundle``
does; it takes seconds, so the Scene page runs it in a worker.
"""

from __future__ import annotations

import logging
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from PySide6.QtCore import QObject, Qt, Signal

from workbench.errors import WorkbenchError

__all__ = ["HeadsetBrowser", "SceneBundleMade", "make_scene_bundle"]

_LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class SceneBundleMade:
    """A bundle :func:`make_scene_bundle` wrote.

    Attributes
    ----------
    folder : Path
    lights : tuple of str
        The source ids it holds (what the headset can switch between).
    left_out : tuple of str
        Sources of the page that a bundle cannot hold (a user-library spectrum).
    """

    folder: Path
    lights: tuple
    left_out: tuple


def make_scene_bundle(profile, source_ids, folder) -> SceneBundleMade:
    """Write ``profile``'s runtime bundle with the lightbooth cube and ``source_ids`` into ``folder``.

    Sources from the user's library (``user-…``) have no library id a bundle can
    name, and are left out (:attr:`SceneBundleMade.left_out`).

    Raises
    ------
    WorkbenchError
        When no source is left, or the bundle cannot be written.
    """
    from workbench.export import write_bundle
    from workbench.illuminants.user_library import USER_ID_PREFIX
    from workbench.vr.scene_cubes import SCENE_CUBE, scene_cube

    ids = [str(s) for s in source_ids]
    lights = tuple(s for s in ids if not s.startswith(USER_ID_PREFIX))
    left_out = tuple(s for s in ids if s.startswith(USER_ID_PREFIX))
    if not lights:
        raise WorkbenchError("the headset's lightbooth needs a library source (your own spectra cannot go "
                             "into a bundle); add one on the Illuminants page")
    summary = write_bundle(profile, folder, light_ids=lights, cubes=[(SCENE_CUBE, scene_cube())])
    return SceneBundleMade(Path(summary.directory), tuple(summary.lights) if summary.lights else lights,
                           left_out)


class HeadsetBrowser(QObject):
    """The shared WebXR server (module doc).

    Attributes
    ----------
    status_changed(object)
        The server's :class:`~workbench.vr.server.ServerStatus` after every
        change (the page connecting, entering VR, the scene switched in the
        headset, a measurement attached), in the GUI thread; ``None`` once the
        server has stopped.
    """

    status_changed = Signal(object)
    _from_server = Signal(object, object)  # (server, status), emitted on the server's thread

    def __init__(self, parent=None):
        super().__init__(parent)
        self._server = None
        self._bundle_folder: Path | None = None
        self._scratch: list = []
        self._from_server.connect(self._forward, Qt.ConnectionType.QueuedConnection)

    # -- state ----------------------------------------------------------------------------------
    @property
    def server(self):
        """The running :class:`~workbench.vr.server.WebXRServer`, or ``None``."""
        return self._server

    @property
    def running(self) -> bool:
        return self._server is not None

    @property
    def bundle_folder(self) -> Path | None:
        """The bundle the running server serves, or ``None``."""
        return self._bundle_folder if self._server is not None else None

    def status(self):
        """The running server's :class:`~workbench.vr.server.ServerStatus` now, or ``None``."""
        return None if self._server is None else self._server.status()

    IN_USE_MESSAGE = "a calibration is showing its patches on the page: cancel it first"
    """What a page says when the server is asked to stop while :attr:`in_use`."""

    @property
    def in_use(self) -> bool:
        """Whether a measurement is showing its patches on the page (the server must not stop)."""
        status = self.status()
        return status is not None and status.patches is not None

    # -- life -----------------------------------------------------------------------------------
    def start(self, host: str, port: int, bundle=None, source: str | None = None):
        """Serve the page on ``host:port`` (with ``bundle``'s lightbooth, showing ``source`` first if it
        holds it); return the server.

        A server already running there is kept (and restarted with ``bundle``
        when one is given and it serves another); one running elsewhere is
        stopped first. Either needs no measurement to be using it.

        Raises
        ------
        InputError
            The port cannot be bound (the message names it and what to do).
        WorkbenchError
            A measurement is using the running server.
        """
        from workbench.vr.server import WebXRServer

        current = self._server
        bundle = None if bundle is None else Path(bundle)
        if current is not None:
            same_place = (current.host, current.port) == (host, port) or (current.host == host and port == 0)
            if same_place and (bundle is None or bundle == self._bundle_folder):
                return current
            if self.in_use:
                raise WorkbenchError("the headset's browser is showing a calibration's patches: wait for the "
                                     "calibration to end (or cancel it) before the server changes")
            if bundle is None:
                bundle = self._bundle_folder
            self._close_server()
        server = WebXRServer(host=host, port=port, bundle=bundle)
        if source is not None and server.bundle is not None and source in server.bundle.light_ids():
            server.set_scene(source)  # before the page can load the scene
        server.start()
        self._server, self._bundle_folder = server, bundle
        server.add_listener(lambda status, server=server: self._from_server.emit(server, status))
        _LOG.info("headset browser: serving %s%s", server.url, f" with the bundle {bundle}" if bundle else "")
        self.status_changed.emit(server.status())
        return server

    def stop(self) -> None:
        """Stop serving (the page is told); idempotent."""
        if self._server is None:
            return
        self._close_server()
        self.status_changed.emit(None)

    def scratch_folder(self) -> Path:
        """A new temporary folder (for a bundle), removed by :meth:`shutdown`."""
        folder = Path(tempfile.mkdtemp(prefix="vr-workbench-headset-"))
        self._scratch.append(folder)
        return folder

    def shutdown(self) -> None:
        """Stop the server and remove the temporary bundles (the window's teardown)."""
        self.stop()
        for folder in self._scratch:
            shutil.rmtree(folder, ignore_errors=True)
        self._scratch = []

    def _close_server(self) -> None:
        server, self._server = self._server, None
        server.close()

    # -- scene ----------------------------------------------------------------------------------
    def set_scene(self, source: str | None = None, level: int | None = None) -> bool:
        """Show ``source`` (and ``level``) in the headset, if the server serves a bundle holding it;
        returns whether it was sent."""
        server = self._server
        if server is None or server.bundle is None:
            return False
        if source is not None and source not in server.bundle.light_ids():
            return False
        scene = server.status().scene
        if scene.get("source") == source and (level is None or scene.get("level") == level):
            return True
        server.set_scene(source, level)
        return True

    def _forward(self, server, status) -> None:
        if server is self._server:  # a stopped server's last words are not news
            self.status_changed.emit(status)
