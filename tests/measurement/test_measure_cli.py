"""``measure`` end to end: the real CS-2000 driver against the emulator on a pty.

Includes the crash test: a simulated run in a subprocess is killed with SIGKILL
at a random point and resumed; every planned patch must then be present
exactly once and the journal lines written before the kill unchanged.
"""

import os
import random
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from instruments.cs2000 import CS2000, ErrorFault, VanishFault
from instruments.headset import SimulatedHeadset, radiance_to_XYZ
from instruments.patch_display import SimulatedPatchDisplay
from instruments.patch_server import PatchServer
from workbench.cli import main
from workbench.measurement.journal import read_journal
from workbench.measurement.plans import measurement_plan
from workbench.measurement.runner import JOURNAL_NAME, MeasurementRun, RunAborted
from workbench.measurement.simulation import (
    InstrumentTimingModel,
    modelled_plan_duration_s,
    open_simulated_instrument,
)
from workbench.session import read_session_csv

PLAN = measurement_plan("quick", seed=9)


def _measure(*args):
    return [sys.executable, "-m", "workbench", "measure", "--simulate", *args]


def _assert_every_patch_once(out_dir, plan_length):
    journal = read_journal(out_dir / JOURNAL_NAME)
    ok = sorted(r.index for r in journal.records if r.ok)
    assert ok == list(range(plan_length)), "each planned patch measured exactly once"
    return journal


@pytest.mark.parametrize("kill_seed", [1, 2])
def test_a_run_killed_at_a_random_point_resumes_without_repeating_or_losing_a_patch(tmp_path, kill_seed):
    args = ["--plan", "quick", "--seed", "9", "--time-scale", "0.001", "--out", str(tmp_path)]
    journal_path = tmp_path / JOURNAL_NAME
    kill_after = random.Random(kill_seed).randint(1, len(PLAN) - 2)  # records written before the kill
    process = subprocess.Popen(_measure(*args), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and process.poll() is None:
        if journal_path.exists() and journal_path.read_bytes().count(b"\n") >= 1 + kill_after:
            break
        time.sleep(0.002)
    assert process.poll() is None, f"the run ended before the kill: {process.stderr.read().decode()}"
    os.kill(process.pid, signal.SIGKILL)
    process.wait(10)
    assert process.returncode == -signal.SIGKILL
    before = journal_path.read_bytes()
    complete = before[: before.rfind(b"\n") + 1]
    killed = read_journal(journal_path)
    assert kill_after <= len(killed.records) < len(PLAN)

    resumed = subprocess.run(_measure("--resume", "--out", str(tmp_path), "--time-scale", "0"),
                             capture_output=True, text=True, timeout=120)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{len(PLAN)} of {len(PLAN)} patches measured, 0 failed" in resumed.stdout
    after = journal_path.read_bytes()
    assert after.startswith(complete), "journal lines written before the kill are unchanged"
    journal = _assert_every_patch_once(tmp_path, len(PLAN))
    assert len(journal.records) == len(PLAN) and len(journal.resumes) == 1
    assert [r.t_s for r in journal.records] == sorted(r.t_s for r in journal.records)
    session = read_session_csv(tmp_path / "session.csv")
    assert len(session) == len(PLAN) and session.spectra.shape == (len(PLAN), 401)


def _settings():
    return {"simulated": True, "effects": {}, "time_scale": 0.0}


def test_the_port_vanishing_mid_run_names_the_patch_keeps_the_journal_and_resume_finishes(tmp_path, capsys):
    vanish_at = 6  # the port disappears when the 6th MEAS,1 arrives: patch #5 is in flight
    with open_simulated_instrument(seed=9, faults=[VanishFault(command="MEAS,1", nth=vanish_at)]) as sim:
        with pytest.raises(RunAborted) as aborted:
            with CS2000(sim.server.port, timeout_s=2.0) as meter:
                run = MeasurementRun.start(tmp_path, PLAN, SimulatedPatchDisplay(sim.headset), meter,
                                           settings=_settings(), clock=lambda header, journal: sim.clock)
                list(run.events())
    message = str(aborted.value)
    assert (f"port vanished while measuring patch 6 of {len(PLAN)} ({PLAN.patches[5].describe()}, "
            "journal index 5)") in message
    assert "--resume" in message
    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert not journal.truncated and [r.index for r in journal.records] == list(range(5))
    assert all(r.ok for r in journal.records)

    assert main(["measure", "--simulate", "--resume", "--out", str(tmp_path)]) == 0
    assert f"{len(PLAN)} of {len(PLAN)} patches measured" in capsys.readouterr().out
    _assert_every_patch_once(tmp_path, len(PLAN))


def test_an_instrument_error_fails_the_patch_the_run_continues_and_resume_remeasures_it(tmp_path, capsys):
    with open_simulated_instrument(seed=9, faults=[ErrorFault("ER83", command="MEAS,1", nth=3)]) as sim:
        with CS2000(sim.server.port, timeout_s=2.0) as meter:
            run = MeasurementRun.start(tmp_path, PLAN, SimulatedPatchDisplay(sim.headset), meter,
                                       settings=_settings(), clock=lambda header, journal: sim.clock)
            summary = list(run.events())[-1].summary
    (failed,) = summary.failed
    assert failed.index == 2 and "ER83" in failed.reason
    assert summary.measured == len(PLAN) - 1
    assert main(["measure", "--simulate", "--resume", "--out", str(tmp_path)]) == 0
    _assert_every_patch_once(tmp_path, len(PLAN))


def test_a_simulated_run_measures_what_the_headset_emits(tmp_path, capsys):
    assert main(["measure", "--simulate", "--plan", "quick", "--seed", "9", "--effect", "black-offset:0.01",
                 "--out", str(tmp_path)]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"measure: finished: {len(PLAN)} of {len(PLAN)} patches measured, 0 failed; simulated")
    session = read_session_csv(tmp_path / "session.csv")
    expected = radiance_to_XYZ(SimulatedHeadset({"black-offset": 0.01}).radiance(session.rgb))
    assert np.allclose(session.XYZ, expected, rtol=0.01, atol=0.01)  # the emulator adds 0.2 % noise
    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert journal.header.settings["effects"] == {"black-offset": 0.01}
    assert journal.header.instrument["model"] == "CS-2000"
    # the session clock is the instrument's modelled time, not the (instant) wall clock
    modelled = modelled_plan_duration_s(PLAN, SimulatedHeadset({"black-offset": 0.01}))
    assert journal.session_end_s() == pytest.approx(modelled, rel=0.01)


def test_temporal_drift_shows_in_the_white_references_of_a_run_at_time_scale_zero(tmp_path, capsys):
    assert main(["measure", "--simulate", "--plan", "quick", "--seed", "2", "--effect", "temporal-drift:0.06",
                 "--out", str(tmp_path)]) == 0
    whites = read_session_csv(tmp_path / "session.csv").select("white")
    assert whites.t_s[-1] > 300  # modelled minutes, although the run took a second
    headset = SimulatedHeadset({"temporal-drift": 0.06})
    headset.session_length_s = modelled_plan_duration_s(PLAN, headset)
    expected = [radiance_to_XYZ(headset.radiance([255, 255, 255], t))[1] for t in whites.t_s]
    assert np.allclose(whites.XYZ[:, 1], expected, rtol=0.005)
    assert whites.XYZ[0, 1] < whites.XYZ[-1, 1] - 0.3  # still warming up at the first white


def test_patches_can_go_to_a_vr_application_over_tcp(tmp_path, capsys):
    app_headset = SimulatedHeadset()
    shown = []
    with PatchServer(lambda rgb: (shown.append(rgb), app_headset.show(rgb))) as server:
        server.start()
        host, port = server.address
        assert main(["measure", "--simulate", "--plan", "quick", "--seed", "9",
                     "--display", f"tcp:{host}:{port}", "--out", str(tmp_path)]) == 0
    assert shown == [list(p.rgb) for p in PLAN.patches]
    assert "via tcp:127.0.0.1" in read_journal(tmp_path / JOURNAL_NAME).header.display


def test_a_plan_file_is_measured_as_listed(tmp_path, capsys):
    plan_file = tmp_path / "plan.csv"
    plan_file.write_text("kind,r,g,b\nwhite,255,255,255\nmixture,10,200,30\nblack,0,0,0\n")
    assert main(["measure", "--simulate", "--plan-file", str(plan_file), "--out", str(tmp_path / "run")]) == 0
    session = read_session_csv(tmp_path / "run" / "session.csv")
    assert list(session.kind) == ["white", "mixture", "black"]


@pytest.mark.parametrize("args, message", [
    (["--simulate", "--effect", "sparkle"], "unknown headset effect 'sparkle'; use one of black-offset"),
    (["--port", "/dev/null", "--display", "simulated"], "--display simulated needs --simulate"),
    (["--port", "/dev/null"], "--port needs --display tcp:HOST:PORT"),
    (["--port", "/dev/null", "--effect", "black-offset"], "apply to --simulate only"),
    (["--simulate", "--display", "tcp:nowhere"], "not understood; use simulated or tcp:HOST:PORT"),
    (["--simulate", "--resume"], "no such journal"),
])
def test_command_line_mistakes_are_one_clear_message(tmp_path, capsys, args, message):
    assert main(["measure", *args, "--out", str(tmp_path)]) == 2
    assert message in capsys.readouterr().err


def test_a_second_run_into_the_same_directory_must_say_resume(tmp_path, capsys):
    args = ["measure", "--simulate", "--plan-file", str(tmp_path / "p.csv"), "--out", str(tmp_path / "run")]
    (tmp_path / "p.csv").write_text("kind,r,g,b\nwhite,255,255,255\n")
    assert main(args) == 0
    assert main(args) == 2
    assert "add --resume" in capsys.readouterr().err
    assert main(["measure", "--simulate", "--resume", "--plan", "paper", "--seed", "1",
                 "--out", str(tmp_path / "run")]) == 2
    assert "differs from the plan given now" in capsys.readouterr().err


def test_the_timing_model_waits_longer_on_dark_patches():
    headset, timing = SimulatedHeadset(), InstrumentTimingModel()
    white = timing.measurement_s(headset.radiance([255, 255, 255]))
    dark = timing.measurement_s(headset.radiance([0, 20, 0]))
    assert 2 <= white < dark <= 252
