"""Fixtures shared by the GUI tests (each module skips itself where Qt cannot open a window)."""

from __future__ import annotations

import gc

import pytest


@pytest.fixture
def window(qtbot, tmp_path, monkeypatch):
    """The workbench's main window on an empty workspace, with its own configuration folder;
    shut down, closed and collected after the test."""
    from PySide6.QtWidgets import QApplication

    from workbench.gui.main_window import MainWindow
    from workbench.gui.settings import WindowSettings
    from workbench.workspace import Workspace

    monkeypatch.setenv("VR_WORKBENCH_CONFIG_DIR", str(tmp_path / "config"))
    window = MainWindow(Workspace(), WindowSettings(tmp_path / "config"))
    window.show()
    yield window
    window.shutdown()
    window.close()
    window.deleteLater()
    QApplication.processEvents()
    gc.collect()
