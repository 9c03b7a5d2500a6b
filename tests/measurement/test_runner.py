"""The runner with a scripted meter: journaling, failures, aborts, cancel, pause, resume, exports."""

import threading

import numpy as np
import pytest

import workbench.measurement.journal as journal_module
from instruments.cs2000 import AngleKnobError, PortVanishedError
from instruments.patch_display import PatchDisplayError
from workbench.errors import InputError
from workbench.measurement.journal import read_journal
from workbench.measurement.plans import measurement_plan
from workbench.measurement.runner import (
    JOURNAL_NAME,
    MeasurementRun,
    PatchMeasured,
    PatchStarted,
    RunAborted,
    RunFinished,
    RunPaused,
    RunResumed,
    RunStarted,
)
from workbench.session import read_session_csv, write_session_csv

from .conftest import RecordingDisplay, ScriptedMeter

PLAN = measurement_plan("quick", seed=5)


def _angle_knob_error():
    return AngleKnobError("ER83", b"ER83", "the measuring-angle knob is between positions",
                          "turn the knob to a click stop")


def _run_all(run):
    return list(run.events())


def test_a_run_measures_every_patch_journals_it_and_exports(tmp_path, display, meter):
    events = _run_all(MeasurementRun.start(tmp_path, PLAN, display, meter, display_name="sim"))
    assert isinstance(events[0], RunStarted) and events[0].total == len(PLAN) and events[0].done == 0
    summary = events[-1].summary
    assert isinstance(events[-1], RunFinished) and summary.status == "finished"
    assert summary.measured == len(PLAN) and summary.failed == ()
    measured = [e for e in events if isinstance(e, PatchMeasured)]
    assert [e.done for e in measured] == list(range(1, len(PLAN) + 1))
    assert display.shown == [list(p.rgb) for p in PLAN.patches]

    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert [r.index for r in journal.records] == list(range(len(PLAN)))
    assert journal.header.instrument == {"name": "FAKE", "model": "fake meter", "serial": "0001"}
    session = read_session_csv(tmp_path / "session.csv")
    assert list(session.kind) == [p.kind for p in PLAN.patches]
    assert np.array_equal(session.rgb, [p.rgb for p in PLAN.patches])
    assert np.allclose(session.XYZ, [r.XYZ for r in journal.records], rtol=1e-5)
    assert session.spectra.shape == (len(PLAN), 401) and session.wavelengths[-1] == 780
    assert (tmp_path / "session.ti3").is_file()
    assert set(summary.outputs) == {tmp_path / n for n in ("journal.jsonl", "session.csv", "session.ti3")}


def test_each_measurement_is_on_disk_before_the_next_patch_is_shown(tmp_path, headset, meter, monkeypatch):
    fsyncs = []  # the journal's size at each fsync of the journal file
    real_fsync = journal_module.os.fsync
    journal_path = tmp_path / JOURNAL_NAME

    def fsync(fd):
        real_fsync(fd)
        if journal_path.exists() and journal_module.os.fstat(fd).st_ino == journal_path.stat().st_ino:
            fsyncs.append(journal_path.stat().st_size)

    monkeypatch.setattr(journal_module.os, "fsync", fsync)

    class CountingDisplay(RecordingDisplay):
        def show(self, rgb_dac):
            self.fsyncs_before.append(len(fsyncs))
            super().show(rgb_dac)

    display = CountingDisplay(headset)
    display.fsyncs_before = []
    _run_all(MeasurementRun.start(tmp_path, PLAN, display, meter))
    assert display.fsyncs_before == [1 + i for i in range(len(PLAN))]  # header, then one per patch
    lines = journal_path.read_bytes().splitlines(keepends=True)
    assert fsyncs == [sum(map(len, lines[: n + 1])) for n in range(len(lines))]  # each line whole on disk


def test_a_failed_patch_is_journaled_with_its_reason_and_the_run_continues(tmp_path, display, headset):
    meter = ScriptedMeter(headset, errors={3: _angle_knob_error()})
    summary = _run_all(MeasurementRun.start(tmp_path, PLAN, display, meter))[-1].summary
    assert summary.measured == len(PLAN) - 1
    (failed,) = summary.failed
    assert failed.index == 2 and "ER83" in failed.reason and "knob" in failed.reason
    assert "patch 3 of 28 (ramp-r (51, 0, 0), journal index 2): CS-2000 ER83" in summary.one_line()
    assert len(read_session_csv(tmp_path / "session.csv")) == len(PLAN) - 1

    again = ScriptedMeter(headset)
    summary = _run_all(MeasurementRun.resume_session(tmp_path, display, again))[-1].summary
    assert again.calls == 1 and summary.failed == () and summary.measured == len(PLAN)
    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert [r.status for r in journal.records if r.index == 2] == ["failed", "ok"]


def test_repeated_failures_stop_the_run(tmp_path, display, headset):
    meter = ScriptedMeter(headset, errors={n: _angle_knob_error() for n in (2, 3, 4, 5)})
    run = MeasurementRun.start(tmp_path, PLAN, display, meter, max_consecutive_failures=3)
    with pytest.raises(RunAborted, match=r"3 patches failed in a row, the last patch 4 of 28 .*journal index 3.*--resume"):
        _run_all(run)
    assert [r.status for r in read_journal(tmp_path / JOURNAL_NAME).records] == ["ok", "failed", "failed", "failed"]


def test_the_port_vanishing_stops_the_run_naming_the_patch_and_resume_finishes(tmp_path, display, headset):
    meter = ScriptedMeter(headset, errors={5: PortVanishedError("/dev/ttyACM0", "MEAS,1")})
    with pytest.raises(RunAborted) as aborted:
        _run_all(MeasurementRun.start(tmp_path, PLAN, display, meter))
    message = str(aborted.value)
    assert "port vanished while measuring patch 5 of 28 (ramp-r (153, 0, 0), journal index 4)" in message
    assert "/dev/ttyACM0" in message and "--resume" in message
    assert aborted.value.index == 4
    before = (tmp_path / JOURNAL_NAME).read_bytes()
    assert [r.index for r in read_journal(tmp_path / JOURNAL_NAME).records] == [0, 1, 2, 3]

    summary = _run_all(MeasurementRun.resume_session(tmp_path, display, ScriptedMeter(headset)))[-1].summary
    assert summary.measured == len(PLAN)
    assert (tmp_path / JOURNAL_NAME).read_bytes().startswith(before)
    indices = [r.index for r in read_journal(tmp_path / JOURNAL_NAME).records]
    assert sorted(indices) == list(range(len(PLAN)))


def test_a_display_failure_stops_the_run_naming_the_patch(tmp_path, headset, meter):
    display = RecordingDisplay(headset, fail_on=3, error=PatchDisplayError("the VR application went away"))
    with pytest.raises(RunAborted, match=r"display failed to show patch 3 of 28 .*went away.*--resume"):
        _run_all(MeasurementRun.start(tmp_path, PLAN, display, meter))
    assert meter.calls == 2


def test_cancel_stops_without_exports_and_resume_continues(tmp_path, display, meter, headset):
    run = MeasurementRun.start(tmp_path, PLAN, display, meter)
    events = []
    for event in run.events():
        events.append(event)
        if isinstance(event, PatchMeasured) and event.done == 5:
            run.cancel()
    summary = events[-1].summary
    assert summary.status == "cancelled" and summary.measured == 5
    assert not (tmp_path / "session.csv").exists()
    summary = _run_all(MeasurementRun.resume_session(tmp_path, display, ScriptedMeter(headset)))[-1].summary
    assert summary.status == "finished" and summary.measured == len(PLAN)


def test_cancel_during_a_measurement_is_passed_to_the_meter(tmp_path, display, headset):
    class CancelledWhileMeasuring(ScriptedMeter):
        def measure(self, progress=None, cancel=None):
            if self.calls == 2:
                run.cancel()  # the user presses Cancel (from the GUI thread) while the instrument measures
                assert cancel.is_set()
            return super().measure(progress, cancel)  # raises MeasurementCancelled, as the driver does

    run = MeasurementRun.start(tmp_path, PLAN, display, CancelledWhileMeasuring(headset))
    summary = _run_all(run)[-1].summary
    assert summary.status == "cancelled" and summary.measured == 2
    assert len(read_journal(tmp_path / JOURNAL_NAME).records) == 2


def test_pause_and_resume_from_another_thread(tmp_path, display, meter):
    run = MeasurementRun.start(tmp_path, PLAN, display, meter)
    calls_at = {}
    events = []
    for event in run.events():
        events.append(type(event))
        if isinstance(event, PatchMeasured) and event.done == 3:
            run.pause()
            threading.Timer(0.2, run.resume).start()
        elif isinstance(event, RunPaused):
            calls_at["paused"] = meter.calls
        elif isinstance(event, RunResumed):
            calls_at["resumed"] = meter.calls
    i = events.index(RunPaused)
    assert events[i - 1] is PatchMeasured and events[i + 1] is RunResumed and events[i + 2] is PatchStarted
    assert calls_at == {"paused": 3, "resumed": 3}
    assert events[-1] is RunFinished


def test_resume_refuses_another_plan_or_instrument(tmp_path, display, meter, headset):
    run = MeasurementRun.start(tmp_path, PLAN, display, meter)
    for event in run.events():
        if isinstance(event, PatchMeasured):
            run.cancel()
    with pytest.raises(InputError, match="differs from the plan given now.*same ones"):
        MeasurementRun.resume_session(tmp_path, display, meter, plan=measurement_plan("quick", seed=6))
    with pytest.raises(InputError, match="instrument serial '0001', this one is '0002'"):
        MeasurementRun.resume_session(tmp_path, display, ScriptedMeter(headset, serial="0002"))


class FakeWallClock:
    """A monotonic clock that moves only when the (fake) instrument takes time."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_the_eta_appears_after_the_first_patch_and_counts_dark_patches_longer(tmp_path, display, headset):
    wall = FakeWallClock()

    class SlowInTheDark(ScriptedMeter):
        def measure(self, progress=None, cancel=None):
            result = super().measure(progress, cancel)
            wall.now += 20.0 if result.Lv < 1.0 else 1.0  # seconds the instrument takes, on the injected clock
            return result

    run = MeasurementRun.start(tmp_path, PLAN, display, SlowInTheDark(headset), wall_clock=wall)
    events = list(run.events())
    starts = [e for e in events if isinstance(e, PatchStarted)]
    assert starts[0].eta_s is None
    assert all(e.eta_s is not None and e.eta_s >= 0 for e in starts[1:])
    # after the ramps, the remaining validation colours and whites are brighter: the ETA per patch drops
    first_validation = next(e for e in starts if e.patch.kind == "validation")
    remaining = len(PLAN) - first_validation.index
    assert first_validation.eta_s / remaining < starts[1].eta_s / (len(PLAN) - 1)
    assert events[-1].summary.wall_s == wall.now - 100.0  # the run's wall time is the injected clock's too


class NotComputableSpectrum(ScriptedMeter):
    """Sends NaN (the driver's reading of "-9.9999e9") at 380-384 nm on call ``spectrum_on``;
    also NaN XYZ when ``xyz_too``."""

    def __init__(self, headset, spectrum_on, xyz_too=False):
        super().__init__(headset)
        self.spectrum_on, self.xyz_too = spectrum_on, xyz_too

    def measure(self, progress=None, cancel=None):
        result = super().measure(progress, cancel)
        if self.calls == self.spectrum_on:
            result.radiance = result.radiance.copy()
            result.radiance[:5] = np.nan
            if self.xyz_too:
                result.XYZ = np.full(3, np.nan)
        return result


def test_a_spectrum_that_is_not_computable_is_left_out_with_a_warning_and_xyz_kept(tmp_path, display, headset):
    summary = _run_all(MeasurementRun.start(tmp_path, PLAN, display, NotComputableSpectrum(headset, 4)))[-1].summary
    assert summary.measured == len(PLAN) and summary.failed == ()
    journal = read_journal(tmp_path / JOURNAL_NAME)
    record = journal.records[3]
    assert record.ok and record.spectrum is None and record.XYZ is not None and record.Lv > 0
    assert "could not compute the spectral radiance at 5 of 401 wavelengths (380-384 nm)" in record.warning
    assert "spectrum is left out" in record.warning
    assert all(r.warning == "" and r.spectrum is not None for r in journal.records if r.index != 3)
    assert len(read_session_csv(tmp_path / "session.csv")) == len(PLAN)


def test_a_patch_whose_xyz_and_spectrum_are_not_computable_fails_with_both_reasons(tmp_path, display, headset):
    meter = NotComputableSpectrum(headset, 4, xyz_too=True)
    summary = _run_all(MeasurementRun.start(tmp_path, PLAN, display, meter))[-1].summary
    (failed,) = summary.failed
    assert failed.index == 3 and "could not compute XYZ" in failed.reason
    assert "spectral radiance at 5 of 401 wavelengths (380-384 nm)" in failed.reason


def test_a_resume_uses_the_journal_it_is_given(tmp_path, display, meter, headset, monkeypatch):
    import workbench.measurement.runner as runner_module

    run = MeasurementRun.start(tmp_path, PLAN, display, meter)
    for event in run.events():
        if isinstance(event, PatchMeasured) and event.done == 3:
            run.cancel()
    journal = read_journal(tmp_path / JOURNAL_NAME)
    monkeypatch.setattr(runner_module, "read_journal", lambda path: pytest.fail("the journal was read again"))
    run = MeasurementRun.resume_session(tmp_path, display, ScriptedMeter(headset), journal=journal,
                                        resume_details={"note": "test"})
    summary = _run_all(run)[-1].summary
    assert summary.measured == len(PLAN)
    monkeypatch.undo()
    again = read_journal(tmp_path / JOURNAL_NAME)
    assert again.resumes[-1]["note"] == "test" and again.resumes[-1]["measured_before"] == 3
    # the session CSV, written from memory, is byte for byte what the journal on disk gives
    expected = write_session_csv(journal_module.journal_to_session(again), tmp_path / "from-disk.csv")
    assert (tmp_path / "session.csv").read_bytes() == expected.read_bytes()
