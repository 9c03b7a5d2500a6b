"""One set of protocol tests for both patch servers, over real sockets.

``python``: the reference server (``instruments/patch_server.py``); ``unity-mono``: the Unity
package's C# core (``workbench/export/runtime/unity/Runtime/Patch/``, what ``VrPatchServer``
runs in the headset) under mono with a headless presenter. Both are started the way a user
starts them, ``python -m instruments.patch_server --impl IMPL --port 0``, and must give the same
replies, byte for byte, to the workbench's own client and to a hostile one. Also here: the
patch shader's colour-space arithmetic run under mono, and the package's patch-server C#
compiled against the UnityEngine test double.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from instruments.patch_display import MAX_LINE_BYTES, PATCH_PROTOCOL, TcpPatchDisplay
from instruments.patch_server import PatchServer
from instruments.unity_mono import build_program, mono_command, patch_core_sources
from workbench.cli import main as workbench_main
from workbench.session import read_session_csv

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "workbench" / "export" / "runtime" / "unity"
STUB = ROOT / "tests" / "export" / "unity_stub" / "UnityEngine.cs"
IMPLS = ("python", "unity-mono")
HELLO = {"cmd": "hello", "id": 1, "protocol": PATCH_PROTOCOL, "client": "protocol-test"}


def _mono_present() -> bool:
    return shutil.which("mono") is not None and shutil.which("mcs") is not None


def _need_mono():
    if not _mono_present():
        pytest.skip("mono/mcs not found: install the Debian packages mono-mcs mono-runtime (make test installs them)")


class RunningServer:
    """``python -m instruments.patch_server --impl IMPL --port 0 --record FILE`` as a child process."""

    def __init__(self, impl: str, folder: Path, *extra: str):
        self.impl = impl
        self.record = folder / f"record-{impl}.jsonl"
        self.process = subprocess.Popen(
            [sys.executable, "-m", "instruments.patch_server", "--impl", impl, "--port", "0",
             "--idle-timeout", "60", "--record", str(self.record), *extra],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
            env={**os.environ, "PYTHONUNBUFFERED": "1"},
        )
        lines: list[str] = []
        reader = threading.Thread(target=lambda: lines.append(self.process.stdout.readline()), daemon=True)
        reader.start()
        reader.join(120.0)  # the first run compiles the C# core
        if not lines or not lines[0]:
            self.stop()
            raise AssertionError(f"{impl} server did not start: {self.process.stderr.read()[-2000:]}")
        self.banner = lines[0]
        self.port = int(self.banner.rsplit(":", 1)[1])
        self.address = ("127.0.0.1", self.port)

    def records(self) -> list[dict]:
        if not self.record.exists():
            return []
        return [json.loads(line) for line in self.record.read_text().splitlines()]

    def stop(self) -> str:
        self.process.terminate()
        try:
            _, err = self.process.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            _, err = self.process.communicate()
        return err


@pytest.fixture(scope="module")
def servers(tmp_path_factory):
    """Started on first use, one per implementation, for the whole module."""
    folder = tmp_path_factory.mktemp("patch-servers")
    running: dict[str, RunningServer] = {}

    def get(impl: str) -> RunningServer:
        if impl == "unity-mono":
            _need_mono()
        if impl not in running:
            running[impl] = RunningServer(impl, folder)
        return running[impl]

    yield get
    for server in running.values():
        server.stop()


@pytest.fixture(params=IMPLS)
def server(request, servers) -> RunningServer:
    return servers(request.param)


class Client:
    """A raw protocol client: bytes out, reply lines in, each with a deadline."""

    def __init__(self, address, timeout: float = 5.0):
        self.sock = socket.create_connection(address, timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.buffer = b""

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def request(self, message: dict) -> dict:
        self.send(json.dumps(message).encode() + b"\n")
        return json.loads(self.line())

    def line(self) -> bytes:
        while b"\n" not in self.buffer:
            chunk = self.sock.recv(65536)
            if not chunk:
                raise ConnectionError(f"closed by the server; pending {self.buffer!r}")
            self.buffer += chunk
        line, _, self.buffer = self.buffer.partition(b"\n")
        return line

    def at_eof(self) -> bool:
        """The server has closed (after whatever is buffered)."""
        return self.buffer == b"" and self.sock.recv(65536) == b""

    def close(self) -> None:
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# --- started the way a user starts them ------------------------------------------------------

def test_both_print_where_they_listen_as_the_reference_server_always_has(server):
    assert server.banner == f"patch server ({PATCH_PROTOCOL}) listening on tcp:127.0.0.1:{server.port}\n"


def test_hello_show_bye_through_the_workbench_s_client(server):
    before = len(server.records())
    with TcpPatchDisplay(*server.address, timeout_s=5.0) as display:
        expected = {"python": "simulated OLED HMD", "unity-mono": "Unity VrPatchServer core under mono"}[server.impl]
        assert expected in display.display_name
        for rgb in ([255, 0, 0], [12, 34, 56], [0, 0, 0]):
            display.show(rgb)
        display.show([255, 255, 255], window=0.1, surround=[64, 64, 64])
    shown = server.records()[before:]
    assert [(r["rgb"], r["window"], r["surround"], r["eye"]) for r in shown] == [
        ([255, 0, 0], 1.0, [0, 0, 0], "both"), ([12, 34, 56], 1.0, [0, 0, 0], "both"),
        ([0, 0, 0], 1.0, [0, 0, 0], "both"), ([255, 255, 255], 0.1, [64, 64, 64], "both")]


# --- the replies, byte for byte ------------------------------------------------------------------

SCRIPT = [
    # (request line, expected reply line); the hello reply's display differs and is checked apart
    (b'{"cmd": "show", "id": 2, "rgb": [255, 128, 0]}', b'{"ok": true, "id": 2}'),
    (b'{"cmd": "show", "id": 3, "rgb": [255, 255, 255], "window": 0.03, "surround": [128, 128, 128]}',
     b'{"ok": true, "id": 3}'),
    (b'{"cmd": "show", "id": 4, "rgb": [10, 20, 30], "eye": "left"}', b'{"ok": true, "id": 4}'),
    (b'{"cmd": "show", "id": 5, "rgb": [1, 2, 3], "eye": "both"}', b'{"ok": true, "id": 5}'),
    (b'{"cmd": "target", "id": 6}', b'{"ok": true, "id": 6}'),
    (b'{"cmd": "target", "id": 7, "eye": "right"}', b'{"ok": true, "id": 7}'),
    (b'{"cmd": "show", "id": 8, "rgb": [1, 2, 3], "gamma": 2.2}',
     b'{"ok": false, "id": 8, "error": "unknown field \'gamma\' in show; this server knows cmd, id, rgb, window, '
     b'surround, eye"}'),
    (b'{"cmd": "target", "id": 9, "rgb": [1, 2, 3]}',
     b'{"ok": false, "id": 9, "error": "unknown field \'rgb\' in target; this server knows cmd, id, eye"}'),
    (b'{"cmd": "show", "id": 10, "rgb": [1, 2]}',
     b'{"ok": false, "id": 10, "error": "patch rgb [1, 2] must be three DAC values [r, g, b]"}'),
    (b'{"cmd": "show", "id": 11, "rgb": [1, 2, 256]}',
     b'{"ok": false, "id": 11, "error": "patch rgb [1, 2, 256] must be integers 0..255 (8-bit DAC values)"}'),
    (b'{"cmd": "show", "id": 12, "rgb": [1, 2.5, 3]}',
     b'{"ok": false, "id": 12, "error": "patch rgb [1, 2.5, 3] must be integers 0..255 (8-bit DAC values)"}'),
    (b'{"cmd": "show", "id": 13, "rgb": [1, true, 3]}',
     b'{"ok": false, "id": 13, "error": "patch rgb [1, true, 3] must be integers 0..255 (8-bit DAC values)"}'),
    (b'{"cmd": "show", "id": 14, "rgb": ["1", 2, 3]}',
     b'{"ok": false, "id": 14, "error": "patch rgb [\\"1\\", 2, 3] must be integers 0..255 (8-bit DAC values)"}'),
    (b'{"cmd": "show", "id": 15}', b'{"ok": false, "id": 15, "error": "patch rgb null must be three DAC values [r, g, b]"}'),
    (b'{"cmd": "show", "id": 16, "rgb": [1, 2, 3], "window": 0}',
     b'{"ok": false, "id": 16, "error": "patch window 0 must be a number in (0, 1] (the fraction of the field)"}'),
    (b'{"cmd": "show", "id": 17, "rgb": [1, 2, 3], "window": "0.5"}',
     b'{"ok": false, "id": 17, "error": "patch window \\"0.5\\" must be a number in (0, 1] (the fraction of the field)"}'),
    (b'{"cmd": "show", "id": 18, "rgb": [1, 2, 3], "window": 0.5, "surround": [0, 0, -1]}',
     b'{"ok": false, "id": 18, "error": "patch surround [0, 0, -1] must be integers 0..255 (8-bit DAC values)"}'),
    (b'{"cmd": "show", "id": 19, "rgb": [1, 2, 3], "eye": "middle"}',
     b'{"ok": false, "id": 19, "error": "patch eye \\"middle\\" must be \\"left\\", \\"right\\" or \\"both\\""}'),
    (b'{"cmd": "target", "id": 20, "eye": 1}',
     b'{"ok": false, "id": 20, "error": "patch eye 1 must be \\"left\\", \\"right\\" or \\"both\\""}'),
    (b'{"cmd": "wiggle", "id": 21}',
     b'{"ok": false, "id": 21, "error": "unknown cmd \'wiggle\'; use hello, show, target or bye"}'),
    (b'{"id": 22}', b'{"ok": false, "id": 22, "error": "a request must carry a \'cmd\': hello, show, target or bye"}'),
    (b'{"cmd": "hello", "id": 23, "protocol": "vr-workbench-patch/0"}',
     b'{"ok": false, "id": 23, "protocol": "vr-workbench-patch/1", "error": "this server speaks vr-workbench-patch/1"}'),
    (b'not json', b'{"ok": false, "id": null, "error": "not JSON: not json"}'),
    (b'', b'{"ok": false, "id": null, "error": "not JSON: "}'),
    (b'{"cmd": "show", "id": 24, "rgb": [1, 2, 3],}',
     b'{"ok": false, "id": null, "error": "not JSON: {\\"cmd\\": \\"show\\", \\"id\\": 24, \\"rgb\\": [1, 2, 3],}"}'),
    (b'{"cmd": "show", "id": 25, "rgb": [1, 2, 3], "window": NaN}',
     b'{"ok": false, "id": null, "error": "not JSON: {\\"cmd\\": \\"show\\", \\"id\\": 25, \\"rgb\\": [1, 2, 3], '
     b'\\"window\\": NaN}"}'),
    (b'{"cmd": "show", "id": 26, "id": 27}',
     b'{"ok": false, "id": null, "error": "not JSON: {\\"cmd\\": \\"show\\", \\"id\\": 26, \\"id\\": 27}"}'),
    (b'\xff\xfe{}', b'{"ok": false, "id": null, "error": "not JSON: \\ufffd\\ufffd{}"}'),
    (b'[1, 2, 3]', b'{"ok": false, "id": null, "error": "a request must be a JSON object"}'),
    (b'{"cmd": "show", "rgb": [1, 2, 3]}',
     b'{"ok": false, "id": null, "error": "a request must carry an integer \'id\'; got none"}'),
    (b'{"cmd": "show", "id": "7", "rgb": [1, 2, 3]}',
     b'{"ok": false, "id": null, "error": "a request must carry an integer \'id\'; got \\"7\\""}'),
    (b'{"cmd": "show", "id": 7.5, "rgb": [1, 2, 3]}',
     b'{"ok": false, "id": null, "error": "a request must carry an integer \'id\'; got 7.5"}'),
    (b'{"cmd": "\xc3\xa9t\xc3\xa9", "id": 28}',
     b'{"ok": false, "id": 28, "error": "unknown cmd \'\\u00e9t\\u00e9\'; use hello, show, target or bye"}'),
    (b'  {"cmd": "show", "id": 29, "rgb": [4, 5, 6]}  \r', b'{"ok": true, "id": 29}'),
    (b'{"cmd": "show", "id": 12345678901234567890, "rgb": [7, 8, 9]}', b'{"ok": true, "id": 12345678901234567890}'),
]


def test_every_reply_is_the_protocol_s_byte_for_byte(server):
    before = len(server.records())
    with Client(server.address) as client:
        hello = client.request(HELLO)
        assert hello["ok"] is True and hello["id"] == 1 and hello["protocol"] == PATCH_PROTOCOL
        client.send(b"".join(line + b"\n" for line, _ in SCRIPT))  # pipelined: answered in order
        replies = [client.line() for _ in SCRIPT]
        assert client.request({"cmd": "bye", "id": 99}) == {"ok": True, "id": 99}
        assert client.at_eof()
    for (request, expected), reply in zip(SCRIPT, replies):
        assert reply == expected, request
    # what reached the presenter: the valid pictures only, in order
    assert server.records()[before:] == [
        {"cmd": "show", "rgb": [255, 128, 0], "window": 1.0, "surround": [0, 0, 0], "eye": "both"},
        {"cmd": "show", "rgb": [255, 255, 255], "window": 0.03, "surround": [128, 128, 128], "eye": "both"},
        {"cmd": "show", "rgb": [10, 20, 30], "window": 1.0, "surround": [0, 0, 0], "eye": "left"},
        {"cmd": "show", "rgb": [1, 2, 3], "window": 1.0, "surround": [0, 0, 0], "eye": "both"},
        {"cmd": "target", "eye": "both"},
        {"cmd": "target", "eye": "right"},
        {"cmd": "show", "rgb": [4, 5, 6], "window": 1.0, "surround": [0, 0, 0], "eye": "both"},
        {"cmd": "show", "rgb": [7, 8, 9], "window": 1.0, "surround": [0, 0, 0], "eye": "both"},
    ]


def test_a_long_value_is_quoted_back_clipped_so_the_reply_stays_a_protocol_line(server):
    name = "x" * 3000
    with Client(server.address) as client:
        reply = client.request({"cmd": "show", "id": 1, "rgb": [1, 2, 3], name: 1})
        assert reply["error"] == f"unknown field '{'x' * 80}...' in show; this server knows cmd, id, rgb, window, " \
                                 "surround, eye"


# --- framing -------------------------------------------------------------------------------------

def _padded(message: dict, total_bytes: int) -> bytes:
    """``message`` as a line of exactly ``total_bytes`` bytes, terminator included."""
    text = json.dumps(message).encode()
    return text + b" " * (total_bytes - len(text) - 1) + b"\n"


def test_the_line_limit_is_4096_bytes_with_the_terminator_and_the_server_skips_past_a_longer_line(server):
    with Client(server.address) as client:
        client.send(_padded({"cmd": "show", "id": 1, "rgb": [1, 1, 1]}, MAX_LINE_BYTES))
        assert json.loads(client.line()) == {"ok": True, "id": 1}
        client.send(_padded({"cmd": "show", "id": 2, "rgb": [2, 2, 2]}, MAX_LINE_BYTES + 1))
        assert json.loads(client.line()) == {
            "ok": False, "id": None,
            "error": "line longer than 4096 bytes (the protocol's limit, terminator included); skipped to its end"}
        # a far longer line, sent in pieces: one error, as soon as it passes the limit
        client.send(b"y" * 5000)
        assert json.loads(client.line())["error"].startswith("line longer than 4096 bytes")
        client.send(b"y" * 20000 + b"\n" + b'{"cmd": "show", "id": 3, "rgb": [3, 3, 3]}\n')
        assert json.loads(client.line()) == {"ok": True, "id": 3}
        assert client.request({"cmd": "show", "id": 4, "rgb": [4, 4, 4]}) == {"ok": True, "id": 4}


def test_partial_lines_across_several_sends_and_crlf(server):
    with Client(server.address) as client:
        line = b'{"cmd": "show", "id": 1, "rgb": [9, 8, 7], "window": 0.25, "surround": [1, 2, 3]}\r\n'
        for start in range(0, len(line), 7):
            client.send(line[start:start + 7])
            time.sleep(0.01)
        assert json.loads(client.line()) == {"ok": True, "id": 1}
        # the end of one request and the start of the next in one send
        two = b'{"cmd": "show", "id": 2, "rgb": [1, 1, 1]}\n{"cmd": "show", "id": 3, "rgb": [2, 2, 2]}\n'
        client.send(two[:30])
        time.sleep(0.05)
        client.send(two[30:70])
        time.sleep(0.05)
        client.send(two[70:])
        assert [json.loads(client.line()) for _ in range(2)] == [{"ok": True, "id": 2}, {"ok": True, "id": 3}]
    assert server.records()[-3]["rgb"] == [9, 8, 7] and server.records()[-3]["window"] == 0.25


# --- clients that vanish, and a second client -----------------------------------------------------

def _hello_works(address) -> None:
    with Client(address) as client:
        assert client.request(HELLO)["ok"] is True
        assert client.request({"cmd": "show", "id": 2, "rgb": [5, 5, 5]}) == {"ok": True, "id": 2}


@pytest.mark.parametrize("vanish", ["mid-line", "before-the-reply", "reset", "silent-close"])
def test_a_client_that_disconnects_mid_request_does_not_stop_the_server(server, vanish):
    client = Client(server.address)
    client.request(HELLO)
    if vanish == "mid-line":
        client.send(b'{"cmd": "show", "id": 2, "rg')
    elif vanish in ("before-the-reply", "reset"):
        client.send(b'{"cmd": "show", "id": 2, "rgb": [200, 100, 50]}\n')
    if vanish == "reset":  # RST instead of FIN
        client.sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    client.close()
    _hello_works(server.address)  # served, not told "busy"
    assert server.process.poll() is None


def test_a_second_client_is_told_who_is_served_and_closed_while_the_first_keeps_working(server):
    with Client(server.address) as first:
        assert first.request(HELLO)["ok"] is True
        first_address = "%s:%s" % first.sock.getsockname()[:2]
        with Client(server.address) as second:
            second.send(json.dumps(HELLO).encode() + b"\n")  # unread by the server: still gets its line
            assert json.loads(second.line()) == {
                "ok": False, "id": None,
                "error": f"busy: this patch server is serving {first_address} (protocol-test) \u2014 one client at a "
                         "time; close that client first"}
            assert second.at_eof()
        assert first.request({"cmd": "show", "id": 2, "rgb": [1, 2, 3]}) == {"ok": True, "id": 2}
        with Client(server.address) as third:  # still busy, still named
            assert "(protocol-test)" in json.loads(third.line())["error"]
        assert first.request({"cmd": "bye", "id": 3}) == {"ok": True, "id": 3}
    _hello_works(server.address)  # right after a bye: served


def test_the_busy_line_names_the_address_alone_before_hello(server):
    with Client(server.address) as first:
        first_address = "%s:%s" % first.sock.getsockname()[:2]
        assert first.request({"cmd": "show", "id": 1, "rgb": [1, 1, 1]})["ok"] is True  # served, no hello yet
        with Client(server.address) as second:
            assert json.loads(second.line())["error"].startswith(
                f"busy: this patch server is serving {first_address} \u2014 one client")
        assert first.request(HELLO)["ok"] is True


def test_the_workbench_s_client_reports_the_busy_server(server):
    from instruments.patch_display import PatchDisplayError

    with TcpPatchDisplay(*server.address, timeout_s=5.0):
        with pytest.raises(PatchDisplayError, match="busy: this patch server is serving 127.0.0.1:"):
            TcpPatchDisplay(*server.address, timeout_s=5.0)


# --- a whole simulated measurement through each server ---------------------------------------------

PLAN_ROWS = ("white,255,255,255", "mixture,10,200,30", "black,0,0,0", "mixture,255,255,255,0.1,64,64,64",
             "ramp-r,255,0,0")


def _measure(tmp_path: Path, server: RunningServer, *extra: str) -> Path:
    plan = tmp_path / "plan.csv"
    plan.write_text("kind,r,g,b,window,sr,sg,sb\n" + "\n".join(
        row if row.count(",") == 7 else row + ",1,0,0,0" for row in PLAN_ROWS) + "\n")
    out = tmp_path / f"run-{server.impl}"
    assert workbench_main(["measure", "--simulate", "--display", f"tcp:127.0.0.1:{server.port}", "--seed", "7",
                           "--plan-file", str(plan), "--out", str(out), *extra]) == 0
    return out


@pytest.mark.parametrize("eye", [None, "left"])
def test_measure_records_the_same_session_against_both_servers(servers, tmp_path, capsys, eye):
    extra = ("--eye", eye) if eye else ()
    sessions, shown = {}, {}
    for impl in IMPLS:
        running = servers(impl)
        before = len(running.records())
        out = _measure(tmp_path, running, *extra)
        sessions[impl] = (out / "session.csv").read_text().splitlines()
        shown[impl] = running.records()[before:]
    assert sessions["python"] == sessions["unity-mono"]
    session = read_session_csv(tmp_path / "run-python" / "session.csv")
    assert len(session.rgb) == len(PLAN_ROWS)
    assert shown["python"] == shown["unity-mono"]
    assert [(r["rgb"], r["window"], r["eye"]) for r in shown["python"]] == [
        ([255, 255, 255], 1.0, eye or "both"), ([10, 200, 30], 1.0, eye or "both"), ([0, 0, 0], 1.0, eye or "both"),
        ([255, 255, 255], 0.1, eye or "both"), ([255, 0, 0], 1.0, eye or "both")]


# --- servers written before an addition -------------------------------------------------------------

@pytest.fixture(params=IMPLS)
def old_server(request):
    """A server without window/surround, eye and target: the reference server's flags, the C# host's."""
    if request.param == "python":
        with PatchServer(lambda rgb: None, apl_patches=False, eye_field=False, target_command=False,
                         idle_timeout_s=10.0) as running:
            running.start()
            yield running.address
        return
    _need_mono()
    process = subprocess.Popen(mono_command("patch-server") + ["--port", "0", "--no-apl", "--no-eye", "--no-target"],
                               stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        port = int(process.stdout.readline().rsplit(":", 1)[1])
        yield ("127.0.0.1", port)
    finally:
        process.terminate()
        process.wait(10)


def test_a_server_written_before_the_additions_refuses_them_by_name(old_server):
    with Client(old_server) as client:
        assert client.request(HELLO)["ok"] is True
        assert client.request({"cmd": "show", "id": 2, "rgb": [1, 2, 3], "eye": "left"}) == {
            "ok": False, "id": 2, "error": "unknown field 'eye' in show; this server knows cmd, id, rgb"}
        assert client.request({"cmd": "show", "id": 3, "rgb": [1, 2, 3], "window": 0.5, "surround": [0, 0, 0]}) == {
            "ok": False, "id": 3, "error": "unknown field 'window' in show; this server knows cmd, id, rgb"}
        assert client.request({"cmd": "target", "id": 4}) == {
            "ok": False, "id": 4, "error": "unknown cmd 'target'; use hello, show or bye"}
        assert client.request({"cmd": "show", "id": 5, "rgb": [1, 2, 3]}) == {"ok": True, "id": 5}


def test_the_reference_server_hands_eye_and_target_to_the_application():
    calls = []
    with PatchServer(lambda rgb, **frame: calls.append((rgb, frame)),
                     show_target=lambda eye: calls.append(("target", eye))) as running:
        running.start()
        with Client(running.address) as client:
            client.request(HELLO)
            client.request({"cmd": "show", "id": 2, "rgb": [1, 2, 3]})
            client.request({"cmd": "show", "id": 3, "rgb": [1, 2, 3], "eye": "right"})
            client.request({"cmd": "show", "id": 4, "rgb": [1, 2, 3], "window": 0.5, "surround": [9, 9, 9],
                            "eye": "left"})
            client.request({"cmd": "target", "id": 5, "eye": "left"})
            assert client.request({"cmd": "show", "id": 6, "rgb": [1, 2, 3], "window": 1.0, "eye": "both"})["ok"]
    assert calls == [([1, 2, 3], {}), ([1, 2, 3], {"eye": "right"}),
                     ([1, 2, 3], {"window": 0.5, "surround": [9, 9, 9], "eye": "left"}), ("target", "left"),
                     ([1, 2, 3], {})]


def test_unity_mono_without_mono_says_what_to_install(tmp_path):
    result = subprocess.run([sys.executable, "-m", "instruments.patch_server", "--impl", "unity-mono", "--port", "0"],
                            capture_output=True, text=True, timeout=60, cwd=ROOT,
                            env={**os.environ, "PATH": str(tmp_path)})
    assert result.returncode == 2
    assert "apt-get install mono-mcs mono-runtime" in result.stderr and "Traceback" not in result.stderr


# --- the patch shader's colour-space arithmetic, run under mono -------------------------------------

def test_every_dac_reaches_the_framebuffer_exactly_in_gamma_and_linear_projects():
    _need_mono()
    mono = shutil.which("mono")
    result = subprocess.run([mono, str(build_program("colour-check"))], capture_output=True, text=True, timeout=120)
    lines = result.stdout.splitlines()
    assert result.returncode == 0, result.stdout + result.stderr
    cases = [line for line in lines if " project, shader " in line]
    assert len(cases) == 6  # Gamma × (float32, half); Linear × (float32, half) × (encode in double, in float32)
    assert all("768/768 exact" in line for line in cases), cases
    assert {line.split(",")[0] for line in cases} == {"Gamma project", "Linear project"}
    # the check can fail: a Linear project writing the Gamma value gets almost every DAC wrong
    control = next(line for line in lines if line.startswith("control:"))
    assert int(control.split("gets ")[1].split("/")[0]) > 200
    assert lines[-1] == "all exact"


def test_the_shader_values_and_their_half_copies_are_numpy_s():
    """PatchColour's values against an independent float64 sRGB decode, and the check's half rounding against numpy."""
    _need_mono()
    mono = shutil.which("mono")
    result = subprocess.run([mono, str(build_program("colour-check")), "--values"], capture_output=True, text=True,
                            timeout=120, check=True)
    rows = [line.split() for line in result.stdout.splitlines()]
    assert len(rows) == 512
    dac = np.array([int(r[0]) for r in rows])
    linear = np.array([r[1] == "1" for r in rows])
    value = np.array([float(r[2]) for r in rows], dtype=np.float32)
    half = np.array([float(r[3]) for r in rows], dtype=np.float32)
    encoded = dac / 255.0
    decoded = np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)
    assert np.array_equal(value, np.where(linear, decoded, encoded).astype(np.float32))
    assert np.array_equal(half, value.astype(np.float16).astype(np.float32))


# --- the Unity side compiles against the UnityEngine test double -------------------------------------

def test_vr_patch_server_compiles_against_the_unityengine_double(tmp_path):
    mcs = shutil.which("mcs")
    if mcs is None:
        pytest.skip("mcs not found: install the Debian package mono-mcs (make test installs it)")
    engine = tmp_path / "UnityEngine.dll"
    subprocess.run([mcs, "-langversion:7.2", "-target:library", "-nologo", f"-out:{engine}", str(STUB)],
                   check=True, capture_output=True, text=True, timeout=180)
    sources = [PACKAGE / "Runtime" / "VrPatchServer.cs", *patch_core_sources()]
    result = subprocess.run([mcs, "-langversion:7.2", "-target:library", "-warnaserror+", "-nologo", f"-r:{engine}",
                             f"-out:{tmp_path / 'VrPatchServer.dll'}", *map(str, sources)],
                            capture_output=True, text=True, timeout=180)
    assert result.returncode == 0, result.stdout + result.stderr
    # the core uses no UnityEngine: it compiles alone
    result = subprocess.run([mcs, "-langversion:7.2", "-target:library", "-warnaserror+", "-nologo",
                             f"-out:{tmp_path / 'Core.dll'}", *map(str, patch_core_sources())],
                            capture_output=True, text=True, timeout=180)
    assert result.returncode == 0, result.stdout + result.stderr


def test_the_patch_shader_is_the_one_the_server_looks_for():
    shader = (PACKAGE / "Runtime" / "Shaders" / "VrPatch.shader").read_text()
    server = (PACKAGE / "Runtime" / "VrPatchServer.cs").read_text()
    name = server.split('ShaderName = "')[1].split('"')[0]
    assert f'Shader "{name}"' in shader
    for prop in ("_PatchColour", "_SurroundColour", "_TargetColour", "_HalfSide", "_Eye", "_Target"):
        assert f'"{prop}"' in server and f"float{'4' if 'Colour' in prop else ''} {prop};" in shader, prop
    assert "using UnityEngine" not in "".join(path.read_text() for path in patch_core_sources())
