"""Patch displays and the JSON-over-TCP patch protocol, over loopback."""

import json
import os
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from instruments.headset import SimulatedHeadset
from instruments.patch_display import (
    PATCH_PROTOCOL,
    MirroredPatchDisplay,
    PatchDisplay,
    PatchDisplayError,
    SimulatedPatchDisplay,
    TcpPatchDisplay,
    validate_patch_rgb,
)
from instruments.patch_server import PatchServer
from instruments.patch_server import main as patch_server_main


@pytest.fixture
def headset():
    return SimulatedHeadset()


@pytest.fixture
def server(headset):
    with PatchServer(headset.show, display_name="test headset", idle_timeout_s=5.0) as running:
        running.start()
        yield running


def test_show_over_loopback_reaches_the_headset(server, headset):
    host, port = server.address
    assert host == "127.0.0.1"
    with TcpPatchDisplay(host, port, timeout_s=2.0) as display:
        assert display.display_name == "test headset"
        for rgb in ([255, 0, 0], [12, 34, 56], [0, 0, 0]):
            display.show(rgb)
            assert np.array_equal(headset.shown, rgb)
        display.show(np.array([7, 8, 9]))
        assert np.array_equal(headset.shown, [7, 8, 9])


def test_the_wire_format_is_one_json_object_per_line_with_matching_ids(server):
    with socket.create_connection(server.address, timeout=2.0) as sock:
        stream = sock.makefile("rwb")
        for request in (
            {"cmd": "hello", "id": 1, "protocol": PATCH_PROTOCOL, "client": "test"},
            {"cmd": "show", "id": 2, "rgb": [1, 2, 3]},
            {"cmd": "show", "id": 3, "rgb": [1, 2]},
            {"cmd": "wiggle", "id": 4},
        ):
            stream.write(json.dumps(request).encode() + b"\r\n")
        stream.write(b"not json\n")
        stream.write(json.dumps({"cmd": "bye", "id": 5}).encode() + b"\n")
        stream.flush()
        replies = [json.loads(line) for line in stream]  # until the server closes after bye
    assert [r["id"] for r in replies] == [1, 2, 3, 4, None, 5]
    assert [r["ok"] for r in replies] == [True, True, False, False, False, True]
    assert replies[0]["protocol"] == PATCH_PROTOCOL and replies[0]["display"] == "test headset"
    assert "three DAC values" in replies[2]["error"]
    assert "unknown cmd 'wiggle'" in replies[3]["error"]


def test_a_bad_patch_is_refused_before_sending_and_the_connection_stays_usable(server, headset):
    with TcpPatchDisplay(*server.address, timeout_s=2.0) as display:
        with pytest.raises(ValueError, match="integers 0..255"):
            display.show([300, 0, 0])
        display.show([4, 5, 6])
        assert np.array_equal(headset.shown, [4, 5, 6])


def test_a_present_that_fails_is_reported_as_refused():
    def broken(rgb):
        raise RuntimeError("the compositor lost the HMD")

    with PatchServer(broken) as server:
        server.start()
        with TcpPatchDisplay(*server.address, timeout_s=2.0) as display:
            with pytest.raises(PatchDisplayError, match="refused 'show'.*compositor lost the HMD"):
                display.show([1, 2, 3])


def _silent_server(answer_hello: bool):
    """A TCP server that accepts, optionally answers hello, then never answers again."""
    listener = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve():
        conn, _ = listener.accept()
        with conn:
            if answer_hello:
                line = conn.makefile("rb").readline()
                request = json.loads(line)
                conn.sendall(json.dumps({"ok": True, "id": request["id"], "protocol": PATCH_PROTOCOL}).encode() + b"\n")
            stop.wait(5.0)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return listener, stop


@pytest.mark.parametrize("answer_hello, waiting_for", [(False, "'hello'"), (True, "'show'")])
def test_every_wait_has_a_deadline_and_the_error_names_the_request(answer_hello, waiting_for):
    listener, stop = _silent_server(answer_hello)
    try:
        port = listener.getsockname()[1]
        with pytest.raises(PatchDisplayError, match=f"did not answer {waiting_for}.*within 0.3 s"):
            display = TcpPatchDisplay("127.0.0.1", port, timeout_s=0.3)
            display.show([1, 2, 3])
    finally:
        stop.set()
        listener.close()


def test_an_absent_server_is_reported_with_host_port_and_fix():
    with socket.create_server(("127.0.0.1", 0)) as probe:
        port = probe.getsockname()[1]  # free once closed
    with pytest.raises(PatchDisplayError, match=f"tcp:127.0.0.1:{port}.*patch_server"):
        TcpPatchDisplay("127.0.0.1", port, timeout_s=1.0)


def test_a_server_speaking_another_version_is_refused():
    listener = socket.create_server(("127.0.0.1", 0))

    def serve():
        conn, _ = listener.accept()
        with conn:
            request = json.loads(conn.makefile("rb").readline())
            conn.sendall(json.dumps({"ok": True, "id": request["id"], "protocol": "patch/0"}).encode() + b"\n")

    threading.Thread(target=serve, daemon=True).start()
    try:
        with pytest.raises(PatchDisplayError, match="speaks 'patch/0'"):
            TcpPatchDisplay("127.0.0.1", listener.getsockname()[1], timeout_s=2.0)
    finally:
        listener.close()


def test_close_says_bye_and_is_idempotent(server):
    display = TcpPatchDisplay(*server.address, timeout_s=2.0)
    display.close()
    display.close()


def test_closing_the_server_drops_a_connected_client_at_once(headset):
    server = PatchServer(headset.show, idle_timeout_s=60.0).start()
    display = TcpPatchDisplay(*server.address, timeout_s=2.0)
    closer = threading.Thread(target=server.close)
    closer.start()
    closer.join(5.0)
    assert not closer.is_alive()
    with pytest.raises(PatchDisplayError):
        display.show([1, 1, 1])


class RecordingServer(PatchServer):
    """A reference server that records the commands it answers, in order."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.commands = []

    def answer(self, line):
        self.commands.append(json.loads(line).get("cmd"))
        return super().answer(line)


def test_a_connection_dropped_while_idle_is_reconnected_once_with_hello(headset):
    with RecordingServer(headset.show, idle_timeout_s=0.1) as server:
        server.start()
        with TcpPatchDisplay(*server.address, timeout_s=2.0) as display:
            display.show([1, 2, 3])
            deadline = time.monotonic() + 5.0
            while server.client_socket.fileno() != -1 and time.monotonic() < deadline:
                time.sleep(0.02)  # a long pause: the server drops the silent client
            assert server.client_socket.fileno() == -1, "the server did not drop the idle client"
            display.show([9, 8, 7])
            assert np.array_equal(headset.shown, [9, 8, 7])
    assert server.commands[:4] == ["hello", "show", "hello", "show"]


def test_a_server_that_drops_every_show_fails_after_one_reconnection():
    listener = socket.create_server(("127.0.0.1", 0))
    connections = []

    def serve():
        for _ in range(3):
            try:
                conn, _ = listener.accept()
            except OSError:
                return
            connections.append(conn)
            stream = conn.makefile("rb")
            request = json.loads(stream.readline())  # hello
            conn.sendall(json.dumps({"ok": True, "id": request["id"], "protocol": PATCH_PROTOCOL}).encode() + b"\n")
            stream.readline()  # show: hang up instead of answering
            stream.close()
            conn.close()

    threading.Thread(target=serve, daemon=True).start()
    try:
        display = TcpPatchDisplay("127.0.0.1", listener.getsockname()[1], timeout_s=2.0)
        with pytest.raises(PatchDisplayError, match="closed the connection during 'show'"):
            display.show([1, 2, 3])
        assert len(connections) == 2  # the first and one reconnection, no more
    finally:
        listener.close()


def test_the_idle_timeout_help_gives_the_real_default(capsys):
    with pytest.raises(SystemExit):
        patch_server_main(["--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "(default 600)" in help_text and "(default 60)" not in help_text


def test_simulated_and_mirrored_displays(headset):
    other = SimulatedHeadset()
    display = MirroredPatchDisplay(SimulatedPatchDisplay(headset), SimulatedPatchDisplay(other))
    assert isinstance(display, PatchDisplay)
    display.show([10, 20, 30])
    assert np.array_equal(headset.shown, [10, 20, 30]) and np.array_equal(other.shown, [10, 20, 30])
    assert "simulated OLED HMD" in display.describe()
    with pytest.raises(ValueError, match="integers 0..255"):
        display.show([10.5, 20, 30])


@pytest.mark.parametrize("bad", [[1, 2], [1, 2, 256], [1, 2, -1], ["a", 2, 3], None, [1.2, 2, 3]])
def test_validate_patch_rgb_refuses_bad_patches(bad):
    with pytest.raises(ValueError):
        validate_patch_rgb(bad)


def test_the_reference_server_runs_from_the_command_line():
    process = subprocess.Popen(
        [sys.executable, "-m", "instruments.patch_server", "--port", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        line = process.stdout.readline()
        assert "listening on tcp:127.0.0.1:" in line
        port = int(line.rsplit(":", 1)[1])
        with TcpPatchDisplay("127.0.0.1", port, timeout_s=5.0) as display:
            assert "simulated OLED HMD" in display.display_name
            display.show([255, 255, 255])
    finally:
        process.terminate()
        process.wait(10)
