"""What the window remembers between sessions: recent files and its layout (platformdirs + QSettings).

The settings live in an INI file in the user's configuration directory
(:func:`platformdirs.user_config_dir`), or in the directory named by the
``VR_WORKBENCH_CONFIG_DIR`` environment variable, or the one given to
:class:`WindowSettings` (tests point it at a temporary directory so that they
never write to the real home).
"""

from __future__ import annotations

import os
from pathlib import Path

import platformdirs
from PySide6.QtCore import QByteArray, QSettings

__all__ = ["CONFIG_DIR_VARIABLE", "MAX_RECENT", "config_dir", "WindowSettings"]

CONFIG_DIR_VARIABLE = "VR_WORKBENCH_CONFIG_DIR"
"""Environment variable that overrides where the settings are kept."""

MAX_RECENT = 10
"""Recent files kept."""


def config_dir(directory: str | os.PathLike | None = None) -> Path:
    """Where the settings live: ``directory``, else ``$VR_WORKBENCH_CONFIG_DIR``, else platformdirs'."""
    if directory is not None:
        return Path(directory)
    if os.environ.get(CONFIG_DIR_VARIABLE):
        return Path(os.environ[CONFIG_DIR_VARIABLE])
    return Path(platformdirs.user_config_dir("vr-workbench", appauthor=False))


class WindowSettings:
    """Recent files and window layout, in ``config_dir()/workbench.ini``."""

    def __init__(self, directory: str | os.PathLike | None = None):
        self.directory = config_dir(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self._settings = QSettings(str(self.directory / "workbench.ini"), QSettings.Format.IniFormat)

    @property
    def path(self) -> Path:
        return Path(self._settings.fileName())

    def recent_files(self) -> list:
        """Most recent first; files that no longer exist are left out."""
        values = self._settings.value("recent/files", [])
        values = [values] if isinstance(values, str) else list(values or [])
        return [v for v in values if Path(v).exists()]

    def add_recent(self, path) -> list:
        path = str(Path(path).resolve())
        files = [path] + [f for f in self.recent_files() if f != path]
        self._settings.setValue("recent/files", files[:MAX_RECENT])
        self._settings.sync()
        return files[:MAX_RECENT]

    def save_layout(self, geometry: QByteArray, state: QByteArray) -> None:
        self._settings.setValue("window/geometry", geometry)
        self._settings.setValue("window/state", state)
        self._settings.sync()

    def layout(self) -> tuple:
        """``(geometry, state)`` as saved, or ``(None, None)``."""
        return self._settings.value("window/geometry"), self._settings.value("window/state")
