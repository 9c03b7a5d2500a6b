"""``measure`` end to end: the real CS-2000 driver against the emulator on a pty.

Includes the crash tests: a simulated run in a subprocess is killed with
SIGKILL at a random point (after a random number of journal lines, or after a
random wall-clock delay, or with a half-written record appended afterwards) and
resumed; every planned patch must then be present exactly once and the journal
lines written before the kill unchanged.
"""

import json
import logging
import os
import random
import signal
import subprocess
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest

import workbench.cli.measure as measure_cli
import workbench.measurement.runner as runner_module
from instruments.cs2000 import CS2000, CS2000Emulator, ErrorFault, VanishFault
from instruments.cs2000 import driver as driver_module
from instruments.headset import SimulatedHeadset, radiance_to_XYZ
from instruments.patch_display import SimulatedPatchDisplay
from instruments.patch_server import PatchServer
from workbench.cli import main
from workbench.measurement.journal import JournalWriter, read_journal
from workbench.measurement.plans import measurement_plan
from workbench.measurement.runner import JOURNAL_NAME, MeasurementRun, PatchMeasured, RunAborted
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


def test_the_timing_model_is_the_emulators_virtual_time():
    headset, timing = SimulatedHeadset({"black-offset": 0.002}), InstrumentTimingModel()
    for rgb in ([255, 255, 255], [0, 0, 0], [0, 20, 0], [5, 0, 0], [128, 64, 200]):
        radiance = headset.radiance(rgb)
        emulator = CS2000Emulator(lambda: radiance, time_scale=1.0, seed=0)
        emulator.feed(b"RMTS,1\r\n", 0.0)
        now, reply = 0.0, emulator.feed(b"MEAS,1\r\n", 0.0)
        while (due := emulator.next_event_time()) is not None:
            now = due
            reply += emulator.poll(now)
        assert reply.startswith(b"OK00,") and reply.endswith(b"OK00\r\n")
        assert timing.measurement_s(radiance) == now  # exactly: the same model, not a copy of it
    with pytest.raises(ValueError, match="ER10"):
        timing.measurement_s(headset.radiance([255, 255, 255]) * 100)


# ----------------------------------------------------------------------------- more crash tests


def _start_run(out_dir, time_scale):
    args = ["--plan", "quick", "--seed", "9", "--time-scale", str(time_scale), "--out", str(out_dir)]
    return subprocess.Popen(_measure(*args), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def _wait_for_lines(process, journal_path, lines, timeout_s=60):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and process.poll() is None:
        if journal_path.exists() and journal_path.read_bytes().count(b"\n") >= lines:
            return
        time.sleep(0.002)


def _kill(process):
    assert process.poll() is None, f"the run ended before the kill: {process.stderr.read().decode()}"
    os.kill(process.pid, signal.SIGKILL)
    process.wait(10)
    assert process.returncode == -signal.SIGKILL


def _resume_and_check(tmp_path, capsys, complete: bytes):
    assert main(["measure", "--simulate", "--resume", "--out", str(tmp_path), "--time-scale", "0"]) == 0
    assert f"{len(PLAN)} of {len(PLAN)} patches measured, 0 failed" in capsys.readouterr().out
    after = (tmp_path / JOURNAL_NAME).read_bytes()
    assert after.startswith(complete), "journal lines written before the kill are unchanged"
    journal = _assert_every_patch_once(tmp_path, len(PLAN))
    assert len(journal.records) == len(PLAN) and len(journal.resumes) == 1 and not journal.truncated
    assert [r.t_s for r in journal.records] == sorted(r.t_s for r in journal.records)
    return after


@pytest.mark.parametrize("kill_seed", [3])
def test_a_run_killed_after_a_random_delay_resumes_without_repeating_or_losing_a_patch(tmp_path, capsys,
                                                                                          kill_seed):
    journal_path = tmp_path / JOURNAL_NAME
    # at 1/200 of real timing the emulator alone makes the quick plan wait 2.4 s after the header
    process = _start_run(tmp_path, time_scale=0.005)
    _wait_for_lines(process, journal_path, 1)
    time.sleep(random.Random(kill_seed).uniform(0.0, 2.0))  # anywhere: between records or mid-write
    _kill(process)
    before = journal_path.read_bytes()
    complete = before[: before.rfind(b"\n") + 1]
    assert len(read_journal(journal_path).records) < len(PLAN)
    _resume_and_check(tmp_path, capsys, complete)


def test_a_half_written_last_record_is_cut_off_by_resume(tmp_path, capsys, caplog):
    journal_path = tmp_path / JOURNAL_NAME
    process = _start_run(tmp_path, time_scale=0.001)
    _wait_for_lines(process, journal_path, 1 + 4)
    _kill(process)
    data = journal_path.read_bytes()
    complete = data[: data.rfind(b"\n") + 1]
    last = json.loads(complete.splitlines()[-1])
    last["index"] += 1
    torn = json.dumps(last).encode()[:300]  # a crash in the middle of writing the next record
    journal_path.write_bytes(complete + torn)
    assert read_journal(journal_path).truncated
    with caplog.at_level(logging.WARNING, logger="workbench.measurement.runner"):
        after = _resume_and_check(tmp_path, capsys, complete)
    assert torn not in after
    assert "ignoring an incomplete last line" in caplog.text


# ----------------------------------------------------------------------------- the instrument, from the CLI


def _plan_file(tmp_path, rows=("white,255,255,255", "mixture,10,200,30")):
    path = tmp_path / "plan.csv"
    path.write_text("kind,r,g,b\n" + "\n".join(rows) + "\n")
    return str(path)


def _inject_faults(monkeypatch, *faults):
    """Make ``measure --simulate`` build its emulator with ``faults``; returns the simulations it opened."""
    opened = []

    def open_with_faults(*args, **kwargs):
        opened.append(open_simulated_instrument(*args, faults=faults, **kwargs))
        return opened[-1]

    monkeypatch.setattr(measure_cli, "open_simulated_instrument", open_with_faults)
    return opened


def test_remote_mode_without_flash_writes_and_the_fallback_to_rmts_1(tmp_path, capsys, monkeypatch):
    plan = _plan_file(tmp_path)
    opened = _inject_faults(monkeypatch)
    assert main(["measure", "--simulate", "--plan-file", plan, "--out", str(tmp_path / "a")]) == 0
    assert opened[0].emulator.received[0] == "RMTS,2" and "RMTS,1" not in opened[0].emulator.received
    assert read_journal(tmp_path / "a" / JOURNAL_NAME).header.settings["remote_mode"] == 2
    opened = _inject_faults(monkeypatch, ErrorFault("ER00", command="RMTS,2"))
    assert main(["measure", "--simulate", "--plan-file", plan, "--out", str(tmp_path / "b")]) == 0
    assert opened[0].emulator.received[:2] == ["RMTS,2", "RMTS,1"] and "IDDR" in opened[0].emulator.received
    assert opened[0].emulator.received[-1] == "RMTS,0"
    assert read_journal(tmp_path / "b" / JOURNAL_NAME).header.settings["remote_mode"] == 1


def test_an_instrument_error_outside_a_measurement_is_one_clear_message(tmp_path, capsys, monkeypatch):
    _inject_faults(monkeypatch, ErrorFault("ER99", command="IDDR"))
    assert main(["measure", "--simulate", "--plan-file", _plan_file(tmp_path), "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: the emulated CS-2000 answered ER99: program abnormality")
    assert "What to do: Switch the instrument off and on" in err and "Traceback" not in err


def test_a_failing_rmts_0_after_a_clean_run_still_ends_with_the_summary(tmp_path, capsys, monkeypatch, caplog):
    _inject_faults(monkeypatch, ErrorFault("ER99", command="RMTS,0"))
    with caplog.at_level(logging.WARNING, logger="instruments.cs2000"):
        assert main(["measure", "--simulate", "--plan-file", _plan_file(tmp_path),
                     "--out", str(tmp_path / "a")]) == 0
    assert "measure: finished: 2 of 2 patches measured, 0 failed" in capsys.readouterr().out
    assert "could not leave remote mode (RMTS,0)" in caplog.text


def _port(device, vid=None, pid=None, description="n/a"):
    return SimpleNamespace(device=device, vid=vid, pid=pid, description=description, product=None)


@pytest.mark.parametrize("ports, message", [
    ([_port("/dev/ttyACM0", 0x132B, 0x2104, "CS-2000"), _port("/dev/ttyACM1", 0x132B, 0x2104, "CS-2000")],
     "2 CS-2000s are connected: /dev/ttyACM0 (CS-2000); /dev/ttyACM1 (CS-2000)"),
    ([_port("/dev/ttyS0", description="ttyS0")], "no CS-2000 (USB 132B:2104) found; serial ports present: /dev/ttyS0"),
])
def test_port_auto_lists_the_candidates_when_it_cannot_choose(tmp_path, capsys, monkeypatch, ports, message):
    monkeypatch.setattr(driver_module.list_ports, "comports", lambda: ports)
    with PatchServer(SimulatedHeadset().show) as server:
        server.start()
        host, port = server.address
        assert main(["measure", "--port", "auto", "--display", f"tcp:{host}:{port}",
                     "--plan-file", _plan_file(tmp_path), "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: the CS-2000 (--port auto): ") and message in err and "What to do" in err
    assert not (tmp_path / "a" / JOURNAL_NAME).exists()


def test_a_second_run_on_a_journal_being_written_is_refused(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["measure", "--simulate", "--plan-file", _plan_file(tmp_path), "--out", str(out)]) == 0
    journal_path = out / JOURNAL_NAME
    with JournalWriter.append_to(read_journal(journal_path)):  # the first run, still writing
        before = journal_path.read_bytes()
        for args in (["--resume"], []):
            assert main(["measure", "--simulate", *args, "--plan-file", _plan_file(tmp_path), "--out", str(out)]) == 2
            assert (f"another measure run is writing {journal_path}; wait for it or stop it"
                    in capsys.readouterr().err)
        assert journal_path.read_bytes() == before


def test_a_resumed_simulation_draws_new_instrument_noise(tmp_path, capsys):
    plan = measurement_plan("quick", seed=4)
    whites = type(plan)("whites", tuple(p for p in plan.patches if p.kind == "white")[:1] * 4, 4)
    settings = {"simulated": True, "effects": {}, "time_scale": 0.0, "noise_seed": 4}
    with open_simulated_instrument(seed=4) as sim, CS2000(sim.server.port, timeout_s=2.0) as meter:
        run = MeasurementRun.start(tmp_path, whites, SimulatedPatchDisplay(sim.headset), meter,
                                   settings=settings, clock=lambda header, journal: sim.clock)
        for event in run.events():
            if isinstance(event, PatchMeasured) and event.done == 2:
                run.cancel()
    assert main(["measure", "--simulate", "--resume", "--out", str(tmp_path)]) == 0
    journal = read_journal(tmp_path / JOURNAL_NAME)
    spectra = [r.spectrum for r in journal.records]
    assert len(spectra) == 4
    # the same white, measured again: had the emulator been seeded as in the first run, the resumed
    # measurements would repeat its noise exactly
    assert not np.array_equal(spectra[2], spectra[0]) and not np.array_equal(spectra[3], spectra[1])
    assert np.allclose(spectra[2], spectra[0], rtol=0.05, atol=1e-6)
    assert journal.resumes[0]["noise_seed"] == [4, 1]


def test_seed_seeds_the_instrument_noise_with_a_plan_file_too(tmp_path, capsys):
    plan = _plan_file(tmp_path)
    runs = {}
    for name, seed in (("a", "5"), ("b", "5"), ("c", "6")):
        assert main(["measure", "--simulate", "--plan-file", plan, "--seed", seed, "--out", str(tmp_path / name)]) == 0
        runs[name] = read_journal(tmp_path / name / JOURNAL_NAME)
    assert runs["a"].header.settings["noise_seed"] == 5
    spectra = {name: np.array([r.spectrum for r in journal.records]) for name, journal in runs.items()}
    assert np.array_equal(spectra["a"], spectra["b"]) and not np.array_equal(spectra["a"], spectra["c"])


def test_a_resume_reads_the_journal_once(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    with open_simulated_instrument(seed=9, faults=[ErrorFault("ER83", command="MEAS,1", nth=2)]) as sim:
        with CS2000(sim.server.port, timeout_s=2.0) as meter:
            run = MeasurementRun.start(out, measurement_plan("quick", seed=9), SimulatedPatchDisplay(sim.headset),
                                       meter, settings=_settings(), clock=lambda header, journal: sim.clock)
            list(run.events())
    reads = []

    def counting(read):
        return lambda path: reads.append(path) or read(path)

    monkeypatch.setattr(measure_cli, "read_journal", counting(measure_cli.read_journal))
    monkeypatch.setattr(runner_module, "read_journal", counting(runner_module.read_journal))
    assert main(["measure", "--simulate", "--resume", "--out", str(out)]) == 0
    assert len(reads) == 1
