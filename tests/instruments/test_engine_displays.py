"""The seed authors' engine conventions (rgb-text: Unity, value-shot: Unreal), byte for byte.

The displays of :mod:`instruments.engine_displays` against the stand-ins of
:mod:`tests.instruments.engine_standins`, then ``measure --simulate`` with the
stand-in driving the simulated headset the emulated CS-2000 measures: every
session row must be the patch the engine showed when the instrument read it.
"""

import socket
import threading
import time

import numpy as np
import pytest

import workbench.cli.measure as measure_cli
from instruments.engine_displays import (
    RgbTextPatchDisplay,
    ValueShotPatchDisplay,
    matlab_number,
    rgb_text_message,
    value_shot_message,
)
from instruments.headset import SimulatedHeadset, radiance_to_XYZ
from instruments.patch_display import AplPatchesUnsupported, PatchDisplayError, show_patch
from tests.instruments.engine_standins import (
    UnityRgbTextStandin,
    UnrealValueShotStandin,
    engine_drives_simulation,
)
from workbench.cli import main
from workbench.measurement.journal import read_journal
from workbench.measurement.plans import measurement_plan
from workbench.measurement.runner import JOURNAL_NAME
from workbench.session import read_session_csv

QUICK = measurement_plan("quick", seed=9)


def _plan_file(tmp_path, rows=("white,255,255,255", "ramp-r,5,0,0", "mixture,10,200,30", "black,0,0,0")):
    path = tmp_path / "plan.csv"
    path.write_text("kind,r,g,b\n" + "\n".join(rows) + "\n")
    return str(path)


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


# -- the wire ------------------------------------------------------------------------------

@pytest.mark.parametrize("dac, text", [(5, "0.019608"), (0, "0"), (255, "1"), (1, "0.0039216"),
                                       (128, "0.50196"), (51, "0.2"), (254, "0.99608")])
def test_channels_are_written_as_matlab_writes_dac_over_255(dac, text):
    # MATLAB: "Value:" + 5/255 -> "Value:0.019608" (string() of a double: 5 significant digits)
    assert matlab_number(dac / 255) == text


def test_the_messages_are_the_authors_bytes():
    assert rgb_text_message([255, 0, 0]) == b"255,0,0"
    assert rgb_text_message([0, 128, 7]) == b"0,128,7"
    assert value_shot_message([5, 0, 0]) == b"Value:0.019608,0,0"
    assert value_shot_message([255, 255, 255]) == b"Value:1,1,1"
    with pytest.raises(ValueError, match="0..255"):
        rgb_text_message([256, 0, 0])


def test_rgb_text_opens_one_connection_per_patch_writes_bare_text_and_waits_the_settle_time():
    waited = []
    with UnityRgbTextStandin() as engine:
        display = RgbTextPatchDisplay(*engine.address, settle_s=2.0, sleep=waited.append)
        for rgb in ([255, 0, 0], [0, 5, 250], [0, 0, 0]):
            display.show(rgb)
        deadline = time.monotonic() + 5
        while len(engine.shown) < 3 and time.monotonic() < deadline:
            time.sleep(0.01)
    assert engine.messages == [b"255,0,0", b"0,5,250", b"0,0,0"]  # each its own connection, no terminator
    assert [rgb for _, rgb in engine.shown] == [[255, 0, 0], [0, 5, 250], [0, 0, 0]]
    assert engine.errors == [] and waited == [2.0, 2.0, 2.0]
    assert "rgb-text:127.0.0.1:" in display.describe() and "2 s settle" in display.describe()


def test_rgb_text_shows_full_field_patches_only():
    display = RgbTextPatchDisplay("127.0.0.1", 9, settle_s=0)
    with pytest.raises(AplPatchesUnsupported, match="cannot show APL patches"):
        show_patch(display, [255, 255, 255], 0.1, [0, 0, 0])


def test_rgb_text_names_the_address_when_nothing_listens():
    port = _free_port()
    display = RgbTextPatchDisplay("127.0.0.1", port, settle_s=0)
    with pytest.raises(PatchDisplayError, match=f"rgb-text:127.0.0.1:{port}:0.*Unity"):
        display.show([1, 2, 3])


@pytest.mark.parametrize("answer_from_send", [1, 2])
def test_value_shot_holds_one_connection_and_sends_again_until_shot(answer_from_send):
    with UnrealValueShotStandin(shot_delay_s=0.01, answer_from_send=answer_from_send) as engine:
        with ValueShotPatchDisplay(*engine.address, timeout_s=5.0, resend_s=0.2) as display:
            for rgb in ([5, 0, 0], [0, 255, 0], [128, 128, 128]):
                display.show(rgb)
                assert engine.showing == rgb  # SHOT came: the engine shows it
        deadline = time.monotonic() + 5
        while not engine.done and time.monotonic() < deadline:
            time.sleep(0.01)
    assert engine.connections == 1 and engine.errors == []
    values = [b"Value:0.019608,0,0", b"Value:0,1,0", b"Value:0.50196,0.50196,0.50196"]
    assert engine.messages == [v for v in values for _ in range(answer_from_send)] + [b"DONE:0"]
    assert display.sends == 3 * answer_from_send
    assert [rgb for _, rgb in engine.shown] == [[5, 0, 0], [0, 255, 0], [128, 128, 128]]


def _mute_engine():
    """An engine that accepts and reads but never says SHOT; returns (address, what it read, stop)."""
    listener = socket.create_server(("127.0.0.1", 0))
    received, stop = bytearray(), threading.Event()

    def serve():
        connection, _ = listener.accept()
        connection.settimeout(0.05)
        with connection:
            while not stop.is_set():
                try:
                    chunk = connection.recv(4096)
                except socket.timeout:
                    continue
                if not chunk:
                    return
                received.extend(chunk)

    threading.Thread(target=serve, daemon=True).start()
    return listener.getsockname()[:2], received, lambda: (stop.set(), listener.close())


def test_value_shot_gives_up_at_its_deadline_naming_the_address_and_the_resends():
    (host, port), received, stop = _mute_engine()
    try:
        display = ValueShotPatchDisplay(host, port, timeout_s=0.5, resend_s=0.2)
        started = time.monotonic()
        with pytest.raises(PatchDisplayError, match=rf"value-shot:127.0.0.1:{port} did not answer SHOT to "
                                                    r"Value:1,0,0 within 0.5 s \(sent 3 times, every 0.2 s\)"):
            display.show([255, 0, 0])
        assert 0.45 < time.monotonic() - started < 2.0
        display.close()
    finally:
        stop()
    assert bytes(received).startswith(b"Value:1,0,0" * 3)


def test_value_shot_names_the_address_when_nothing_listens():
    port = _free_port()
    with pytest.raises(PatchDisplayError, match=f"cannot connect to the engine at value-shot:127.0.0.1:{port}"):
        ValueShotPatchDisplay("127.0.0.1", port, timeout_s=1.0)


# -- measure --simulate against the stand-ins ----------------------------------------------

def _expected_XYZ(rgb):
    return radiance_to_XYZ(SimulatedHeadset().radiance(np.asarray(rgb, dtype=float)))


def _every_row_is_what_the_engine_showed(out_dir, plan_rgb, coupling):
    session = read_session_csv(out_dir / "session.csv")
    assert coupling.measured == plan_rgb  # what the engine showed each time the instrument read the panel
    assert session.rgb.tolist() == plan_rgb
    assert np.allclose(session.XYZ, _expected_XYZ(session.rgb), rtol=0.01, atol=0.01)
    return session


def test_measure_over_rgb_text_records_the_patch_the_engine_showed(tmp_path, monkeypatch, capsys):
    with UnityRgbTextStandin(show_delay_s=0.02) as engine:
        coupling = engine_drives_simulation(monkeypatch, engine)
        host, port = engine.address
        assert main(["measure", "--simulate", "--plan", "quick", "--seed", "9",
                     "--display", f"rgb-text:{host}:{port}:0.12", "--out", str(tmp_path)]) == 0
    plan_rgb = [list(p.rgb) for p in QUICK.patches]
    _every_row_is_what_the_engine_showed(tmp_path, plan_rgb, coupling)
    assert engine.messages == [",".join(map(str, rgb)).encode() for rgb in plan_rgb] and engine.errors == []
    header = read_journal(tmp_path / JOURNAL_NAME).header
    assert header.display.startswith(f"engine via rgb-text:{host}:{port}:0.12 (the authors' Unity convention: "
                                     "R,G,B text, no acknowledgement, 0.12 s settle) + simulated OLED HMD")
    assert header.eye == "both" and header.sync == "none"


def test_a_settle_time_shorter_than_the_engine_takes_measures_the_wrong_patch(tmp_path, monkeypatch, capsys):
    # The check above can fail: the engine shows each patch 0.15 s after it is sent, the client waits 0 s.
    with UnityRgbTextStandin(show_delay_s=0.15) as engine:
        coupling = engine_drives_simulation(monkeypatch, engine)
        host, port = engine.address
        assert main(["measure", "--simulate", "--plan-file", _plan_file(tmp_path), "--seed", "1",
                     "--display", f"rgb-text:{host}:{port}:0", "--out", str(tmp_path / "run")]) == 0
    records = read_journal(tmp_path / "run" / JOURNAL_NAME).ok_records()
    rgb = [list(r.rgb) for r in records]
    assert coupling.measured[0] == [0, 0, 0] and coupling.measured != rgb  # the white read as black
    assert not np.allclose([r.XYZ for r in records], _expected_XYZ(rgb), rtol=0.01, atol=0.01)


@pytest.mark.parametrize("answer_from_send", [1, 2])
def test_measure_over_value_shot_records_the_patch_the_engine_showed(tmp_path, monkeypatch, capsys,
                                                                     answer_from_send):
    monkeypatch.setattr(measure_cli, "VALUE_SHOT_RESEND_S", 0.1)
    with UnrealValueShotStandin(shot_delay_s=0.01, answer_from_send=answer_from_send) as engine:
        coupling = engine_drives_simulation(monkeypatch, engine)
        host, port = engine.address
        assert main(["measure", "--simulate", "--plan", "quick", "--seed", "9",
                     "--display", f"value-shot:{host}:{port}", "--out", str(tmp_path)]) == 0
        deadline = time.monotonic() + 5
        while not engine.done and time.monotonic() < deadline:
            time.sleep(0.01)
    plan_rgb = [list(p.rgb) for p in QUICK.patches]
    _every_row_is_what_the_engine_showed(tmp_path, plan_rgb, coupling)
    assert engine.connections == 1 and engine.errors == [] and engine.done
    assert engine.messages[:answer_from_send] == [value_shot_message(plan_rgb[0])] * answer_from_send
    header = read_journal(tmp_path / JOURNAL_NAME).header
    assert header.display.startswith(f"engine via value-shot:{host}:{port} (the authors' Unreal convention: "
                                     "Value:r,g,b until SHOT, sent again every 0.1 s) + simulated OLED HMD")


def test_an_engine_that_is_not_there_stops_the_run_and_resume_finishes_it(tmp_path, monkeypatch, capsys):
    port = _free_port()
    # The Unity convention has no acknowledgement: the settle time is the only wait for the engine to show
    # a patch, and with 0 s the first reading races the engine's thread on a loaded machine.
    args = ["measure", "--simulate", "--plan-file", _plan_file(tmp_path), "--seed", "1",
            "--display", f"rgb-text:127.0.0.1:{port}:0.12", "--out", str(tmp_path / "run")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert f"cannot send 255,255,255 to the engine at rgb-text:127.0.0.1:{port}:0.12" in err and "--resume" in err
    journal = read_journal(tmp_path / "run" / JOURNAL_NAME)
    assert journal.records == () and len(journal.header.plan) == 4  # the header is kept for --resume
    with UnityRgbTextStandin(port=port) as engine:
        coupling = engine_drives_simulation(monkeypatch, engine)
        assert main([*args, "--resume"]) == 0
    assert coupling.measured == read_session_csv(tmp_path / "run" / "session.csv").rgb.tolist()


@pytest.mark.parametrize("display", ["rgb-text", "value-shot"])
@pytest.mark.parametrize("extra, message", [
    (["--eye", "left"], "--eye left: --display {kind} shows every patch to both eyes"),
    (["--plan", "apl", "--seed", "1"], "the plan apl has {apl} APL patches (a window on a surround"),
    (["--target"], "--target: the authors' {engine} convention ({kind}) has no centring target"),
])
def test_what_the_authors_conventions_cannot_do_is_refused_before_anything_starts(tmp_path, capsys, display,
                                                                                  extra, message):
    engine_class = UnityRgbTextStandin if display == "rgb-text" else UnrealValueShotStandin
    with engine_class() as engine:
        host, port = engine.address
        assert main(["measure", "--simulate", "--display", f"{display}:{host}:{port}", *extra,
                     "--out", str(tmp_path)]) == 2
        time.sleep(0.05)
    err = capsys.readouterr().err
    apl = sum(p.is_apl for p in measurement_plan("apl", seed=1).patches)
    assert message.format(kind=display, engine="Unity" if display == "rgb-text" else "Unreal", apl=apl) in err
    assert engine.messages == [] and not (tmp_path / JOURNAL_NAME).exists()
    if display == "value-shot":
        assert engine.connections == 0


@pytest.mark.parametrize("text, message", [
    ("rgb-text:127.0.0.1", "rgb-text: it needs HOST:PORT"),
    ("rgb-text:127.0.0.1:55001:soon", "settle time 'soon' is not a number of seconds"),
    ("rgb-text:127.0.0.1:55001:-1", "settle time -1 s must lie in 0..60 s"),
    ("value-shot:127.0.0.1", "value-shot: it needs HOST:PORT"),
    ("value-shot:127.0.0.1:8890:2", "value-shot: it needs HOST:PORT"),
])
def test_malformed_engine_addresses_are_one_clear_message(tmp_path, capsys, text, message):
    assert main(["measure", "--simulate", "--display", text, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and "rgb-text:HOST:PORT[:SETTLE_S]" in err and "value-shot:HOST:PORT" in err


def test_parse_display_dispatches_on_the_registry():
    assert measure_cli.parse_display("rgb-text:127.0.0.1:55001", False) == ("rgb-text", ("127.0.0.1", 55001, 2.0))
    assert measure_cli.parse_display("rgb-text:h:1:0.5", False) == ("rgb-text", ("h", 1, 0.5))
    assert measure_cli.parse_display("value-shot:127.0.0.1:8890", True) == ("value-shot", ("127.0.0.1", 8890))
    assert measure_cli.parse_display("tcp:h:2", True) == ("tcp", ("h", 2))
    assert measure_cli.parse_display("window", False) == ("window", (None,))
    assert set(measure_cli.DISPLAY_KINDS) >= {"simulated", "tcp", "window", "rgb-text", "value-shot"}
