"""Re-measuring a finished patch: the journal keeps both records, the newer one wins and says so."""

import json

import numpy as np
import pytest

from workbench.errors import InputError
from workbench.measurement.journal import read_journal
from workbench.measurement.plans import measurement_plan
from workbench.measurement.runner import JOURNAL_NAME, MeasurementRun, PatchMeasured
from workbench.session import read_session_csv

from .conftest import ScriptedMeter

PLAN = measurement_plan("quick", seed=5)


def _finish(run):
    return list(run.events())[-1].summary


def test_remeasuring_a_finished_patch_keeps_both_records_and_the_newer_wins(tmp_path, display, meter, headset):
    assert _finish(MeasurementRun.start(tmp_path, PLAN, display, meter)).status == "finished"
    first = read_journal(tmp_path / JOURNAL_NAME)
    index = 3
    headset.white_luminance = headset.white_luminance * 1.5  # the second measurement differs visibly
    run = MeasurementRun.resume_session(tmp_path, display, ScriptedMeter(headset), remeasure=[index])
    assert run.pending_indices() == [index]
    events = list(run.events())
    measured = [e.record.index for e in events if isinstance(e, PatchMeasured)]
    assert measured == [index]
    assert events[-1].summary.status == "finished" and events[-1].summary.measured == len(PLAN)

    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert len(journal.records) == len(first.records) + 1
    older, newer = [r for r in journal.records if r.index == index]
    assert journal.latest()[index] is newer
    assert journal.superseded_records() == [older]
    assert journal.resumes[-1]["remeasure"] == [index]
    assert newer.XYZ != older.XYZ
    session = read_session_csv(tmp_path / "session.csv")  # re-exported with the newer record
    assert np.allclose(session.XYZ[index], newer.XYZ, rtol=1e-5)
    assert not np.allclose(session.XYZ[index], older.XYZ, rtol=1e-3)


def test_a_plain_resume_of_a_finished_session_measures_nothing_and_writes_no_remeasure(tmp_path, display, meter,
                                                                                     headset):
    _finish(MeasurementRun.start(tmp_path, PLAN, display, meter))
    run = MeasurementRun.resume_session(tmp_path, display, ScriptedMeter(headset))
    assert run.pending_indices() == []
    _finish(run)
    last = json.loads((tmp_path / JOURNAL_NAME).read_text().splitlines()[-1])
    assert last["record"] == "resume" and "remeasure" not in last


def test_remeasure_outside_the_plan_is_refused_naming_the_index(tmp_path, display, meter, headset):
    _finish(MeasurementRun.start(tmp_path, PLAN, display, meter))
    with pytest.raises(InputError, match=f"index {len(PLAN)}"):
        MeasurementRun.resume_session(tmp_path, display, ScriptedMeter(headset), remeasure=[len(PLAN)])
