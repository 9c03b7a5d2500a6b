"""``measure --sync``, ``--eye`` and ``--target``: what reaches the instrument and the display, and what is recorded."""

import io
import json
import socket
import threading

import pytest

import workbench.cli.measure as measure_cli
from instruments.cs2000 import CS2000, CS2000Emulator, SyncMode, serve_on_pty
from instruments.patch_display import (
    EyeUnsupported,
    MirroredPatchDisplay,
    SimulatedPatchDisplay,
    TargetUnsupported,
    TcpPatchDisplay,
    encode_message,
    show_target,
)
from workbench.cli import main
from workbench.measurement.journal import read_journal
from workbench.measurement.runner import JOURNAL_NAME
from workbench.measurement.simulation import open_simulated_instrument
from workbench.profile import load_profile
from workbench.session import read_session_csv


def _plan_file(tmp_path, rows=("white,255,255,255", "mixture,10,200,30", "black,0,0,0")):
    path = tmp_path / "plan.csv"
    path.write_text("kind,r,g,b\n" + "\n".join(rows) + "\n")
    return str(path)


def _capture_simulations(monkeypatch):
    opened = []

    def opening(*args, **kwargs):
        opened.append(open_simulated_instrument(*args, **kwargs))
        return opened[-1]

    monkeypatch.setattr(measure_cli, "open_simulated_instrument", opening)
    return opened


def _measure(tmp_path, *args, out="run"):
    return main(["measure", "--simulate", "--plan-file", _plan_file(tmp_path), "--seed", "3", *args,
                 "--out", str(tmp_path / out)])


# -- sync -----------------------------------------------------------------------------------

@pytest.mark.parametrize("given, sent", [
    (["--sync", "internal:90"], "SCMS,1,9000"),
    (["--sync", "internal:72.5"], "SCMS,1,7250"),
    (["--sync", "external"], "SCMS,2"),
    (["--sync", "none"], "SCMS,0"),
    ([], "SCMS,0"),
])
def test_sync_reaches_the_instrument_as_scms_before_the_first_measurement(tmp_path, monkeypatch, capsys,
                                                                          given, sent):
    opened = _capture_simulations(monkeypatch)
    assert _measure(tmp_path, *given) == 0
    received = opened[0].emulator.received
    first_meas = received.index("MEAS,1")
    assert sent in received[:first_meas] and received.index("SCMR") < received.index(sent)
    if sent != "SCMS,0":  # the instrument was in no sync: put back when the run ends
        assert received[received.index(sent) + 1:].count("SCMS,0") == 1
        assert received.index("SCMS,0") > len(received) - 1 - received[::-1].index("MEAS,1")
    expected = SyncMode.parse(given[1] if given else "none").text
    header = read_journal(tmp_path / "run" / JOURNAL_NAME).header
    assert header.sync == expected and header.settings["sync"] == expected
    session = read_session_csv(tmp_path / "run" / "session.csv")
    assert session.metadata["sync"] == expected and session.metadata["eye"] == "both"


def test_the_emulator_keeps_the_sync_mode_it_was_given():
    emulator = CS2000Emulator(lambda: None)
    with serve_on_pty(emulator) as server, CS2000(server.port, timeout_s=5.0) as meter:
        meter.set_sync_mode(1, 90)
        assert meter.sync_mode() == SyncMode(1, 90.0)
        meter.set_sync_mode(2)
        assert meter.sync_mode() == SyncMode(2, None)
    assert "SCMS,1,9000" in emulator.received and "SCMS,2" in emulator.received


@pytest.mark.parametrize("text, message", [
    ("internal:250", "--sync 'internal:250': internal sync takes 20.00-200.00 Hz"),
    ("internal:19.99", "internal sync takes 20.00-200.00 Hz"),
    ("internal:ninety", "internal sync takes 20.00-200.00 Hz"),
    ("internal:90.005", "0.01 Hz steps; give at most two decimals"),
    ("internal", "is not understood; use none, internal:HZ (20-200 Hz, e.g. internal:90) or external"),
    ("90", "is not understood"),
])
def test_a_bad_sync_is_one_clear_message_before_anything_starts(tmp_path, capsys, text, message):
    assert _measure(tmp_path, "--sync", text) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


def test_resume_keeps_the_sessions_sync_and_refuses_another(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    assert _measure(tmp_path, "--sync", "internal:90") == 0
    journal_path = out / JOURNAL_NAME
    lines = journal_path.read_text().splitlines(keepends=True)
    journal_path.write_text("".join(lines[:-1]))  # the last patch is still to be measured
    assert main(["measure", "--simulate", "--resume", "--sync", "none", "--out", str(out)]) == 2
    assert "was measured with --sync internal:90, not none" in capsys.readouterr().err
    opened = _capture_simulations(monkeypatch)
    assert main(["measure", "--simulate", "--resume", "--out", str(out)]) == 0
    assert "SCMS,1,9000" in opened[0].emulator.received  # the session's sync, set again


def test_the_profile_records_the_panel_and_the_sync(tmp_path, capsys):
    assert main(["measure", "--simulate", "--plan", "quick", "--seed", "3", "--eye", "right",
                 "--sync", "internal:90", "--out", str(tmp_path / "run")]) == 0
    profile_path = tmp_path / "p.vrprofile.json"
    assert main(["diagnose", str(tmp_path / "run"), "--export", str(profile_path)]) == 0
    assert json.loads(profile_path.read_text())["measurement"] == {"eye": "right", "sync": "internal:90"}
    assert load_profile(profile_path).measurement == {"eye": "right", "sync": "internal:90"}  # schema-valid


def test_a_session_csv_mixing_panels_is_refused(tmp_path):
    path = tmp_path / "mixed.csv"
    path.write_text("kind,r,g,b,X,Y,Z,eye\nwhite,255,255,255,95,100,108,left\nblack,0,0,0,0,0,0,right\n")
    with pytest.raises(Exception, match="the eye column holds"):
        read_session_csv(path)


# -- eye ------------------------------------------------------------------------------------

def test_eye_is_recorded_for_the_simulated_headset(tmp_path, capsys):
    assert _measure(tmp_path, "--eye", "left") == 0
    assert read_journal(tmp_path / "run" / JOURNAL_NAME).header.eye == "left"
    assert read_session_csv(tmp_path / "run" / "session.csv").metadata["eye"] == "left"
    lines = (tmp_path / "run" / "session.csv").read_text().splitlines()
    assert lines[0].split(",")[7:10] == ["t_s", "eye", "sync"] and lines[1].split(",")[8:10] == ["left", "none"]


def test_a_desktop_window_has_no_eyes(tmp_path, capsys):
    assert main(["measure", "--port", "/dev/null", "--display", "window", "--eye", "left",
                 "--plan-file", _plan_file(tmp_path), "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert "--eye left: --display window a desktop window has no eyes" in err and "--eye both" in err
    assert not (tmp_path / "run").exists()


def test_resume_refuses_another_eye(tmp_path, capsys):
    out = tmp_path / "run"
    assert _measure(tmp_path, "--eye", "left") == 0
    lines = (out / JOURNAL_NAME).read_text().splitlines(keepends=True)
    (out / JOURNAL_NAME).write_text("".join(lines[:-1]))
    assert main(["measure", "--simulate", "--resume", "--eye", "right", "--out", str(out)]) == 2
    assert "measured the left eye's panel, not the right eye's panel" in capsys.readouterr().err


class _ScriptedServer:
    """A patch server that answers hello, then each request as ``answer(request)`` says; keeps what it read."""

    def __init__(self, answer):
        self.answer, self.requests = answer, []
        self._listener = socket.create_server(("127.0.0.1", 0))
        threading.Thread(target=self._serve, daemon=True).start()

    @property
    def address(self):
        return self._listener.getsockname()[:2]

    def _serve(self):
        connection, _ = self._listener.accept()
        with connection, connection.makefile("rb") as lines:
            for line in lines:
                request = json.loads(line)
                self.requests.append(request)
                if request["cmd"] == "hello":
                    reply = {"ok": True, "id": request["id"], "protocol": "vr-workbench-patch/1", "display": "x"}
                else:
                    reply = {"id": request["id"], **self.answer(request)}
                connection.sendall(encode_message(reply))

    def close(self):
        self._listener.close()


_KNOWN_BEFORE_EYE = ("cmd", "id", "rgb", "window", "surround")


def _server_before_eye(request):
    """A server written before the per-eye addition (and before target), as the protocol additions say."""
    if request["cmd"] not in ("show", "bye"):
        return {"ok": False, "error": f"unknown cmd {request['cmd']!r}; use hello, show or bye"}
    unknown = [name for name in request if name not in _KNOWN_BEFORE_EYE]
    if unknown:
        return {"ok": False, "error": f"unknown field {unknown[0]!r} in show; this server knows "
                                      f"{', '.join(_KNOWN_BEFORE_EYE)}"}
    return {"ok": True}


@pytest.mark.parametrize("eye", ["both", "left", "right"])
def test_eye_goes_on_the_wire_only_when_not_both(eye):
    server = _ScriptedServer(lambda request: {"ok": True})
    try:
        with TcpPatchDisplay(*server.address, timeout_s=2.0, eye=eye) as display:
            display.show([1, 2, 3])
            display.show([255, 255, 255], window=0.1, surround=[64, 64, 64])
            display.target()
    finally:
        server.close()
    show, apl, target = server.requests[1:4]
    if eye == "both":
        assert show == {"cmd": "show", "rgb": [1, 2, 3], "id": 2}  # as before the per-eye addition
        assert target == {"cmd": "target", "id": 4}
    else:
        assert show == {"cmd": "show", "rgb": [1, 2, 3], "eye": eye, "id": 2}
        assert apl == {"cmd": "show", "rgb": [255, 255, 255], "window": 0.1, "surround": [64, 64, 64],
                       "eye": eye, "id": 3}
        assert target == {"cmd": "target", "eye": eye, "id": 4}


def test_a_server_from_before_eye_is_told_apart_from_one_without_apl():
    server = _ScriptedServer(_server_before_eye)
    host, port = server.address
    try:
        with TcpPatchDisplay(*server.address, timeout_s=2.0, eye="left") as display:
            with pytest.raises(EyeUnsupported) as refused:
                display.show([255, 255, 255], window=0.1, surround=[0, 0, 0])  # its error lists 'window'
            with pytest.raises(TargetUnsupported, match="cannot show the centring target"):
                display.target()
    finally:
        server.close()
    assert str(refused.value) == (
        f"the display at tcp:{host}:{port} cannot show a patch to one eye (unknown field 'eye' in show; this "
        "server knows cmd, id, rgb, window, surround); update the VR application's patch server, or measure "
        "with --eye both")


def test_targets_reach_only_the_displays_that_draw_one():
    server = _ScriptedServer(lambda request: {"ok": True})
    from instruments.headset import SimulatedHeadset

    try:
        with TcpPatchDisplay(*server.address, timeout_s=2.0) as display:
            show_target(MirroredPatchDisplay(display, SimulatedPatchDisplay(SimulatedHeadset())))
    finally:
        server.close()
    assert [r["cmd"] for r in server.requests] == ["hello", "target", "bye"]
    with pytest.raises(TargetUnsupported, match="has no centring target"):
        show_target(SimulatedPatchDisplay(SimulatedHeadset()))


def test_measure_target_on_a_tcp_display_shows_it_then_waits_for_enter(tmp_path, monkeypatch, capsys):
    server = _ScriptedServer(lambda request: {"ok": True})
    monkeypatch.setattr("sys.stdin", io.StringIO("\n"))
    host, port = server.address
    try:
        assert _measure(tmp_path, "--display", f"tcp:{host}:{port}", "--target", "--eye", "left") == 0
    finally:
        server.close()
    commands = [(r["cmd"], r.get("eye")) for r in server.requests]
    assert commands[:3] == [("hello", None), ("target", "left"), ("show", "left")]
    assert "centring target is shown in the left eye" in capsys.readouterr().err


def test_measure_target_needs_enter_on_stdin(tmp_path, monkeypatch, capsys):
    server = _ScriptedServer(lambda request: {"ok": True})
    monkeypatch.setattr("sys.stdin", io.StringIO(""))  # closed
    host, port = server.address
    try:
        assert _measure(tmp_path, "--display", f"tcp:{host}:{port}", "--target") == 2
    finally:
        server.close()
    assert "--target waits for Enter on standard input, which is closed" in capsys.readouterr().err
    assert [r["cmd"] for r in server.requests if r["cmd"] == "show"] == []  # nothing measured


def test_measure_target_on_the_simulation_says_there_is_nothing_to_aim(tmp_path, capsys):
    assert _measure(tmp_path, "--target") == 0
    assert "the simulated headset has nothing to aim at" in capsys.readouterr().err


# -- the Calibrate page's setup (no Qt) and form --------------------------------------------

def test_a_calibration_setup_measures_with_its_sync_over_the_unreal_convention(tmp_path, monkeypatch):
    import workbench.gui.calibration_setup as calibration_setup
    from tests.instruments.engine_standins import UnrealValueShotStandin
    from workbench.gui.calibration_setup import CalibrationSetup, open_run
    from workbench.measurement.runner import RunFinished

    opened = []
    monkeypatch.setattr(calibration_setup, "open_simulated_instrument",
                        lambda *a, **k: opened.append(open_simulated_instrument(*a, **k)) or opened[-1])
    with UnrealValueShotStandin() as engine:
        setup = CalibrationSetup(tmp_path / "run", display="value-shot", engine_address=engine.address,
                                 plan_name="file", plan_file=_plan_file(tmp_path), sync="internal:90", seed=2)
        with open_run(setup) as run:
            events = list(run.events())
    assert isinstance(events[-1], RunFinished) and events[-1].summary.measured == 3
    received = opened[0].emulator.received
    assert received.index("SCMS,1,9000") < received.index("MEAS,1") and received.count("SCMS,0") == 1
    assert engine.done  # DONE:0 when the run closed the display
    header = read_journal(tmp_path / "run" / JOURNAL_NAME).header
    assert header.sync == "internal:90" and header.eye == "both"
    assert header.display.startswith("engine via value-shot:127.0.0.1:")
    assert [rgb for _, rgb in engine.shown] == [[255, 255, 255], [10, 200, 30], [0, 0, 0]]
    assert setup.describe_display() == f"Unreal project at value-shot:{engine.address[0]}:{engine.address[1]}"


@pytest.mark.parametrize("changes, message", [
    ({"display": "rgb-text", "engine_address": ("127.0.0.1", 55001), "eye": "left"},
     "shows each patch to both eyes"),
    ({"display": "window", "eye": "right"}, "shows each patch to both eyes"),
    ({"display": "rgb-text"}, "needs the engine's host and port (e.g. 127.0.0.1:55001)"),
    ({"sync": "internal:500"}, "internal sync takes 20.00-200.00 Hz"),
    ({"display": "rgb-text", "engine_address": ("h", 1), "settle_s": 99}, "settle time 99 s must lie in 0..60"),
])
def test_a_calibration_setup_refuses_what_its_display_cannot_do(tmp_path, changes, message):
    from workbench.errors import InputError
    from workbench.gui.calibration_setup import CalibrationSetup

    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        CalibrationSetup(tmp_path, **changes)


def test_a_calibration_setup_refuses_apl_patches_for_the_authors_conventions(tmp_path):
    from workbench.errors import InputError
    from workbench.gui.calibration_setup import CalibrationSetup, open_run

    setup = CalibrationSetup(tmp_path, display="rgb-text", engine_address=("127.0.0.1", 9), plan_name="apl")
    with pytest.raises(InputError, match="has APL patches"):
        with open_run(setup):
            pass
    assert not (tmp_path / JOURNAL_NAME).exists()


def test_the_form_offers_the_sync_the_eye_and_the_engines(qtbot, tmp_path):
    pytest.importorskip("PySide6")
    from workbench.gui import measure_window

    if (reason := measure_window.patch_window_unavailable_reason()) is not None:
        pytest.skip(f"Qt cannot open a window here: {reason}")
    from workbench.gui.widgets.calibration_form import CalibrationForm

    form = CalibrationForm()
    qtbot.addWidget(form)
    form.out_dir.setText(str(tmp_path))
    form.sync.setCurrentIndex(form.sync.findData("internal"))
    form.sync_hz.setValue(72.0)
    form.display.setCurrentIndex(form.display.findData("tcp"))
    form.eye.setCurrentIndex(form.eye.findData("left"))
    setup = form.setup()
    assert (setup.sync, setup.eye, setup.display) == ("internal:72", "left", "tcp")
    form.display.setCurrentIndex(form.display.findData("rgb-text"))
    form.settle.setValue(0.5)
    setup = form.setup()
    assert (setup.display, setup.engine_address, setup.settle_s, setup.eye) == ("rgb-text", ("127.0.0.1", 55001),
                                                                                 0.5, "both")
    form.display.setCurrentIndex(form.display.findData("value-shot"))  # the Unreal project's default port
    assert form.setup().engine_address == ("127.0.0.1", 8890) and not form.settle.isVisibleTo(form)
    form.sync.setCurrentIndex(form.sync.findData("none"))
    assert form.setup().sync == "none" and not form.sync_hz.isEnabled()


# -- against the reference patch server (instruments.patch_server) --------------------------

def test_measure_eye_left_with_target_against_the_reference_server(tmp_path, monkeypatch, capsys):
    from instruments.patch_server import PatchServer

    presented, targets = [], []
    monkeypatch.setattr("sys.stdin", io.StringIO("\n"))
    with PatchServer(lambda rgb, **fields: presented.append((rgb, fields.get("eye", "both"))),
                     show_target=targets.append) as server:
        server.start()
        host, port = server.address
        assert _measure(tmp_path, "--display", f"tcp:{host}:{port}", "--eye", "left", "--target") == 0
    assert targets == ["left"]
    assert presented == [([255, 255, 255], "left"), ([10, 200, 30], "left"), ([0, 0, 0], "left")]
    assert read_journal(tmp_path / "run" / JOURNAL_NAME).header.eye == "left"


def test_a_reference_server_from_before_eye_stops_the_run_and_resume_continues(tmp_path, capsys):
    from instruments.patch_server import PatchServer

    with PatchServer(lambda rgb, **fields: None, eye_field=False) as server:
        server.start()
        host, port = server.address
        assert _measure(tmp_path, "--display", f"tcp:{host}:{port}", "--eye", "right") == 2
    err = capsys.readouterr().err
    assert f"the display at tcp:{host}:{port} cannot show a patch to one eye (" in err
    assert "update the VR application's patch server, or measure with --eye both" in err
    assert read_journal(tmp_path / "run" / JOURNAL_NAME).records == ()  # kept for --resume
    with PatchServer(lambda rgb, **fields: None) as server:
        server.start()
        host, port = server.address
        assert main(["measure", "--simulate", "--resume", "--display", f"tcp:{host}:{port}",
                     "--out", str(tmp_path / "run")]) == 0
    assert len(read_journal(tmp_path / "run" / JOURNAL_NAME).ok_records()) == 3


def test_a_reference_server_without_target_is_named(tmp_path, monkeypatch, capsys):
    from instruments.patch_server import PatchServer

    monkeypatch.setattr("sys.stdin", io.StringIO("\n"))
    with PatchServer(lambda rgb, **fields: None, target_command=False) as server:
        server.start()
        host, port = server.address
        assert _measure(tmp_path, "--display", f"tcp:{host}:{port}", "--target") == 2
    assert f"the display at tcp:{host}:{port} cannot show the centring target" in capsys.readouterr().err
