"""The Calibrate page's patch table: every status, DAC and luminance shown whole as a run fills it,
and a failure's reason readable however long it is."""

from __future__ import annotations

import pytest

from tests.gui import require_window

require_window()

from workbench.gui.widgets.patch_table import PatchTable  # noqa: E402
from workbench.measurement.journal import JournalRecord  # noqa: E402
from workbench.measurement.plans import measurement_plan  # noqa: E402

LONG_REASON = ("the instrument answered ER10 (over range) three times: the patch is brighter than the "
               "CS-2000's range with the ND filter out; measure it again with the ND filter in")


def _record(index, patch, ok=True, Lv=None):
    return JournalRecord(index=index, kind=patch.kind, rgb=tuple(patch.rgb), status="ok" if ok else "failed",
                         t_s=float(index), duration_s=1.0, Lv=Lv, reason="" if ok else LONG_REASON)


def _clipped(table) -> list:
    """(row, column, text) of the cells, but the last, whose text is wider than its column."""
    metrics = table.fontMetrics()
    return [(row, column, table.item(row, column).text())
            for row in range(table.rowCount()) for column in range(table.columnCount() - 1)
            if metrics.horizontalAdvance(table.item(row, column).text()) > table.columnWidth(column)]


def test_a_run_filling_the_table_shows_every_cell_whole(qtbot):
    widget = PatchTable()
    qtbot.addWidget(widget)
    widget.resize(600, 400)
    widget.show()
    plan = measurement_plan("paper", seed=3)
    widget.set_plan(plan)
    assert _clipped(widget.table) == []
    for index, patch in enumerate(plan.patches):
        widget.set_measuring(index)
        assert "measuring" in widget.status(index)
        # luminances from a dim black to a bright white, in the table's 4-digit format
        widget.set_record(_record(index, patch, ok=index % 50 != 7, Lv=0.0123 * 10 ** (index % 7)))
    assert _clipped(widget.table) == []
    failed = widget.failed_indices()
    assert failed == [i for i in range(len(plan.patches)) if i % 50 == 7]
    # the reason stays readable where the note column cuts it off at the table's edge
    assert widget.table.item(failed[0], 5).toolTip() == LONG_REASON == widget.note(failed[0])


def test_patches_a_plan_adds_are_shown_whole(qtbot):
    widget = PatchTable()
    qtbot.addWidget(widget)
    plan = measurement_plan("quick", seed=3)
    widget.set_plan(plan)
    wide = type(plan.patches[0])(kind="validation-mixture-added", rgb=(255, 128, 255))
    widget.add_patch(len(plan.patches), wide)
    assert widget.table.rowCount() == len(plan.patches) + 1
    assert _clipped(widget.table) == []
