"""The adaptive plan on the Calibrate page: in the plan list with its budget, target and validation colours,
and, during a real simulated run, the plan growing, the latest decision's reason, the predicted held-out
ΔE00 and the budget left, as the journal records them."""

from __future__ import annotations

import re

import pytest

from tests.gui import require_window

require_window("pyqtgraph")

from PySide6.QtCore import Qt  # noqa: E402

from workbench.gui.calibration_setup import adaptive_estimate  # noqa: E402
from workbench.measurement.adaptive import (  # noqa: E402
    ADAPTIVE_PLAN,
    DEFAULT_VALIDATION,
    adaptive_core_plan,
    held_out_summary,
    plan_state,
)
from workbench.measurement.journal import read_journal  # noqa: E402
from workbench.measurement.runner import JOURNAL_NAME, format_duration  # noqa: E402

pytestmark = pytest.mark.gui

RUN_TIMEOUT_MS = 120_000


def test_adaptive_is_in_the_plan_list_and_its_settings_show_with_it(window):
    form = window.pages["calibrate"].form
    plans = [form.plan.itemData(i) for i in range(form.plan.count())]
    assert ADAPTIVE_PLAN in plans and "paper" in plans
    index = plans.index(ADAPTIVE_PLAN)
    assert form.plan.itemText(index) == f"adaptive (a core of {len(adaptive_core_plan(0))}, then grows)"
    assert "held-out error it removes per second" in form.plan.itemData(index, Qt.ItemDataRole.ToolTipRole)
    form.plan.setCurrentIndex(plans.index("paper"))
    assert not form.budget.isVisibleTo(form) and not form.validation.isVisibleTo(form)
    assert form.setup().plan_name == "paper"

    form.seed.setValue(3)
    form.plan.setCurrentIndex(index)
    for field in (form.budget, form.target, form.validation):
        assert field.isVisibleTo(form)
    assert (form.budget.text(), form.target.text()) == ("auto budget", "no target")
    setup = form.setup()
    assert (setup.plan_name, setup.budget_min, setup.target_dE00, setup.validation) == \
        (ADAPTIVE_PLAN, None, None, DEFAULT_VALIDATION)
    assert len(setup.plan()) == len(adaptive_core_plan(3))
    estimate = adaptive_estimate(setup)
    text = form.estimate.text()
    assert f"Core of <b>{len(adaptive_core_plan(3))} patches</b>" in text
    assert f"about <b>{format_duration(estimate.budget_s)}</b> of instrument time" in text
    assert "(30 % of paper's)" in text and "30 validation colours" in text
    assert f"paper plan's {format_duration(estimate.paper_s)}" in form.estimate.toolTip()
    assert 0.29 < estimate.budget_s / estimate.paper_s <= 0.31 or estimate.budget_s == pytest.approx(
        estimate.core.instrument_s + estimate.validation_s)

    form.budget.setValue(17)
    form.target.setValue(0.5)
    form.validation.setValue(10)
    setup = form.setup()
    assert (setup.budget_min, setup.target_dE00, setup.validation) == (17, 0.5, 10)
    settings = setup.adaptive_settings(3)  # what measure --budget-min 17 --target-dE00 0.5 --validation 10 keeps
    assert (settings.budget_min, settings.target_dE00, settings.validation) == (17, 0.5, 10)
    text = form.estimate.text()
    assert f"your <b>{format_duration(17 * 60)}</b> of instrument time or ΔE00 0.5" in text
    assert "10 validation colours" in text and "the target ΔE00 0.5" in form.estimate.toolTip()


def _counts(text: str) -> int:
    return int(re.search(r"adaptive plan: (\d+) patches so far", text).group(1))


def test_a_simulated_adaptive_run_shows_the_plan_growing_its_reasons_accuracy_and_budget_left(
        qtbot, window, tmp_path):
    page = window.pages["calibrate"]
    form = page.form
    form.instrument.setCurrentIndex(form.instrument.findData("simulated"))
    form.display.setCurrentIndex(form.display.findData("simulated"))
    form.plan.setCurrentIndex(form.plan.findData(ADAPTIVE_PLAN))
    form.seed.setValue(3)
    form.time_scale.setValue(0.001)
    form.budget.setValue(17)
    form.validation.setValue(10)
    form.out_dir.setText(str(tmp_path / "adaptive"))
    seen = []  # what the page showed after each state the worker sent: (state, label text, progress maximum)
    show = page._on_plan_state

    def shown(state):
        show(state)
        # the page processes events while it fits the label (its width), so a later state can be
        # shown inside this call: pair the text with the state the page says it shows
        seen.append((page.plan_state, page.plan_label.text(), page.progress.maximum()))

    page._on_plan_state = shown  # start() connects the worker to it
    qtbot.mouseClick(page.start_button, Qt.MouseButton.LeftButton)
    with qtbot.waitSignal(page.session_loaded, timeout=RUN_TIMEOUT_MS):
        pass
    journal = read_journal(tmp_path / "adaptive" / JOURNAL_NAME)
    final = plan_state(journal)
    core = len(adaptive_core_plan(3))
    assert final.stopped and final.planned == len(journal.header.plan) > core
    measures = [d for d in journal.decisions if d["action"] == "measure"]
    assert measures, "the planner chose no patch: the test shows no growth"

    # the plan grew on the page as the planner decided, never shrinking
    counts = [_counts(text) for _, text, _ in seen]
    assert counts[0] == core and counts[-1] == final.planned
    assert counts == sorted(counts) and len(set(counts)) >= 3
    assert [maximum for *_, maximum in seen][-1] == final.planned == page.progress.maximum()
    assert page.progress.value() == final.planned
    assert page.patches.table.rowCount() == final.planned
    assert all(page.patches.status(i) == "ok" for i in range(final.planned))

    # each decision's reason was shown as it was taken, with its predicted ΔE00 and the budget left
    shown = {}
    for state, text, _ in seen:
        if state.decisions:
            shown[len(state.decisions)] = (state, text)
    assert set(shown) == set(range(1, len(journal.decisions) + 1))
    for number, (state, text) in shown.items():
        decision = journal.decisions[number - 1]
        assert decision["reason"].replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;") in text
        assert f"predicted held-out ΔE00 <b>{decision['predicted_dE00']:.3f}</b>" in text
        assert f"budget left <b>{format_duration(max(decision['budget_s'] - state.elapsed_s, 0))}</b>" in text
        assert f"of {format_duration(17 * 60)}" in text
    first = shown[1][1]
    assert "tone curve" in first or "how the channels combine" in first or "full drive" in first
    # at the end: the journal's state, and the honest score on the validation colours
    text = page.plan_label.text()
    assert f"adaptive plan: {final.planned} patches so far" in text
    assert f"{core} in the core, {final.planned - core} chosen by {len(journal.decisions)} decisions" in text
    assert f"budget left <b>{format_duration(final.time_left_s)}</b>" in text
    assert "the planner stopped, and the validation colours are measured" in text
    assert any("the planner has stopped: measuring the validation colours" in t for _, t, _ in seen)
    assert held_out_summary(tmp_path / "adaptive") in text
    assert "on the 10 validation colours" in text
