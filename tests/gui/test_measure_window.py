"""``measure --display window``: a simulated run whose patches a full-screen Qt window shows."""

import pytest

from tests.gui import require_window

require_window()

from PySide6.QtCore import Slot  # noqa: E402
from PySide6.QtGui import QGuiApplication  # noqa: E402

from workbench.cli import main  # noqa: E402
from workbench.gui import measure_window  # noqa: E402
from workbench.gui.patch_window import PatchWindow  # noqa: E402
from workbench.measurement.journal import read_journal  # noqa: E402
from workbench.measurement.plans import measurement_plan  # noqa: E402
from workbench.measurement.runner import JOURNAL_NAME  # noqa: E402
from workbench.session import read_session_csv  # noqa: E402

pytestmark = pytest.mark.gui


class RecordingPatchWindow(PatchWindow):
    """A patch window that remembers what it painted and what the screen showed of each patch.

    The screen is read back (from the X server) just before the next patch
    replaces the current one, and when the window closes.
    """

    instances = []

    def __init__(self, screen_index):
        super().__init__(screen_index)
        self.painted_rgbs = []
        self.on_screen = []
        self._patches = 0
        self.painted.connect(self.painted_rgbs.append)
        RecordingPatchWindow.instances.append(self)

    def _read_back_centre(self):
        if QGuiApplication.platformName() != "xcb":  # offscreen and friends keep no screen pixels
            return
        centre = self.geometry().center()
        colour = self.screen().grabWindow(0, centre.x(), centre.y(), 1, 1).toImage().pixelColor(0, 0)
        self.on_screen.append([colour.red(), colour.green(), colour.blue()])

    @Slot(list)
    def set_patch(self, rgb):
        if self._patches:
            self._read_back_centre()
        self._patches += 1
        super().set_patch(rgb)

    def closeEvent(self, event):  # noqa: N802 - Qt's name
        self._read_back_centre()
        super().closeEvent(event)


def _in_order(wanted, seen):
    """Whether ``wanted`` occurs in ``seen`` in order (repaints may come in between)."""
    remaining = iter(seen)
    return all(any(rgb == s for s in remaining) for rgb in wanted)


def test_a_simulated_run_shows_every_patch_in_the_window_and_completes(qtbot, tmp_path, capsys, monkeypatch):
    RecordingPatchWindow.instances.clear()
    monkeypatch.setattr(measure_window, "PatchWindow", RecordingPatchWindow)
    plan = measurement_plan("quick", seed=9)

    assert main(["measure", "--simulate", "--display", "window", "--plan", "quick", "--seed", "9",
                 "--time-scale", "0", "--out", str(tmp_path)]) == 0

    assert f"{len(plan)} of {len(plan)} patches measured, 0 failed" in capsys.readouterr().out
    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert sorted(r.index for r in journal.records if r.ok) == list(range(len(plan)))
    assert journal.header.display.startswith("full-screen patch window on ")
    assert len(read_session_csv(tmp_path / "session.csv")) == len(plan)
    (window,) = RecordingPatchWindow.instances
    assert window.screen() is QGuiApplication.screens()[-1]  # the default: the last screen
    wanted = [list(p.rgb) for p in plan.patches]
    assert _in_order(wanted, window.painted_rgbs), "every patch painted, in plan order"
    assert window.rgb == wanted[-1] and not window.isVisible()
    if QGuiApplication.platformName() == "xcb":  # read back from the X server: exact at 24-bit depth
        assert window.on_screen == wanted, "the screen showed each patch's DAC values exactly"


def test_an_unknown_screen_is_one_clear_message(qtbot, tmp_path, capsys):
    assert main(["measure", "--simulate", "--display", "window:7", "--plan", "quick",
                 "--out", str(tmp_path)]) == 2
    assert "no screen 7; choose one of: 0: " in capsys.readouterr().err
    assert not (tmp_path / JOURNAL_NAME).exists()


def test_measure_target_draws_the_target_in_the_window_and_waits_for_enter(qtbot, tmp_path, capsys,
                                                                           monkeypatch):
    import io

    from workbench.gui.patch_window import TARGET_FRAME

    frames = []

    class TargetRecordingWindow(PatchWindow):
        def paintEvent(self, event):  # noqa: N802 - Qt's name
            super().paintEvent(event)
            frames.append(self.last_painted_frame)

    monkeypatch.setattr(measure_window, "PatchWindow", TargetRecordingWindow)
    monkeypatch.setattr("sys.stdin", io.StringIO("\n"))
    plan_file = tmp_path / "plan.csv"
    plan_file.write_text("kind,r,g,b\nwhite,255,255,255\nblack,0,0,0\n")
    assert main(["measure", "--simulate", "--display", "window", "--target", "--plan-file", str(plan_file),
                 "--out", str(tmp_path / "run")]) == 0
    assert "centring target is shown on full-screen patch window" in capsys.readouterr().err
    shown = [f for f in frames if f is not None and f != ([0, 0, 0], 1.0, [0, 0, 0])]
    assert shown[0] == TARGET_FRAME and shown.index(([255, 255, 255], 1.0, [0, 0, 0])) > 0
