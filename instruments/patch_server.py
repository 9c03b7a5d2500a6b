"""Reference server of the patch protocol (``vr-workbench-patch/1``).

A VR developer can read this module as a model of what the VR application must
do (the protocol is documented in :mod:`instruments.patch_display` and
``docs/vr/patch-protocol.md``): listen on loopback, serve one client at a time,
answer ``hello``, and for every ``show`` put the patch on the headset and reply
only once a frame showing it has been presented.

Here the "headset" is a callable, ``present(rgb)``: the command line forwards
the patches to a :class:`instruments.headset.SimulatedHeadset` and logs what it
emits; tests pass the ``show`` of their own simulated headset. In a game engine
``present`` sets the colour of a full-screen unlit quad in front of both eyes,
waits until the compositor has presented that frame, and returns. The optional
fields reach ``present`` as keywords, and only when they are not the default, so
that a ``present(rgb)`` of full-field patches keeps working:

- an APL patch (``window`` < 1): ``present(rgb, window=w, surround=[r, g, b])``;
  the engine fills the field with the surround and draws the patch as a centred
  rectangle of the field's aspect ratio whose sides are ``sqrt(w)`` of the
  field's;
- a patch for one eye: ``present(rgb, eye="left")`` (or ``"right"``); that
  eye's panel shows the patch, the other eye's panel is black.

``target`` (the centring target: a black field with white rings at 10, 20, 30
and 40 % of the field's smaller side in radius, 2-pixel lines, and a cross
through the centre) goes to ``show_target(eye)``; the command line's simulated
headset has no picture to draw it on, so there it is logged and recorded.

Servers written before an addition are played by ``apl_patches=False`` (no
``window``/``surround``), ``eye_field=False`` (no ``eye``) and
``target_command=False`` (no ``target``): they refuse what they do not know by
name, as every server must.

One client at a time: while a client is served, another connection gets one
line, ``{"ok": false, "id": null, "error": "busy: this patch server is serving
HOST:PORT (CLIENT) — one client at a time; close that client first"}``, and is
closed. A client that vanishes is not an error: the server goes back to
listening.

``--impl unity-mono`` runs, instead of this module, the Unity package's C#
patch-server core (``VrPatchServer``'s, from
``workbench/export/runtime/unity/Runtime/Patch/``) under mono with a headless
presenter (:mod:`instruments.unity_mono`): the same protocol, byte for byte,
from the code that runs in the headset.

Run it with::

    python -m instruments.patch_server --port 47800
    python -m instruments.patch_server --impl unity-mono --port 0
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import socket
import socketserver
import sys
import threading
from typing import Callable

from instruments.patch_display import EYES, MAX_LINE_BYTES, PATCH_PROTOCOL, encode_message

__all__ = ["PatchServer", "LineFramer", "IMPLEMENTATIONS", "busy_reply", "main"]

_LOG = logging.getLogger(__name__)

_SHUTDOWN_POLL_S = 0.05  # how often the serving thread looks for a shutdown request
BUSY_GRACE_S = 0.5
"""How long a new connection waits for the current client to finish (one that has just said bye
or hung up) before it is told that the server is busy."""
_BUSY_DRAIN_S = 1.0  # after the busy line, read (and drop) what the refused client sent, then close
_CLIP = 80  # characters of a client's text quoted back in an error

IMPLEMENTATIONS = ("python", "unity-mono")
"""``--impl``: this module, or the Unity package's C# core under mono."""


def _clip(text: str) -> str:
    return text if len(text) <= _CLIP else text[:_CLIP] + "..."


def _json_text(value) -> str:
    """A value as JSON text, as the C# core writes it back (clipped)."""
    return _clip(json.dumps(value, separators=(", ", ": ")))


def busy_reply(peer: str, client: str | None) -> dict:
    """The one reply a second connection gets, naming the client being served."""
    who = f"{peer} ({_clip(client)})" if client else peer
    return {"ok": False, "id": None,
            "error": f"busy: this patch server is serving {who} \u2014 one client at a time; close that client first"}


class LineFramer:
    """Splits received bytes into request lines of at most :data:`MAX_LINE_BYTES` bytes, terminator included.

    Partial lines are kept until their ``\\n`` arrives; ``\\r\\n`` is accepted.
    A line that passes the limit is reported once, as ``None``, as soon as it
    does; its remaining bytes are skipped up to its ``\\n``.
    """

    def __init__(self):
        self._buffer = bytearray()
        self._skipping = False

    def feed(self, data: bytes) -> list[bytes | None]:
        """The complete lines (without terminator) in ``data`` and what came before it; ``None`` for an oversized one."""
        frames: list[bytes | None] = []
        view = memoryview(data)
        while view:
            newline = bytes(view).find(b"\n")
            chunk, view = (view, memoryview(b"")) if newline < 0 else (view[:newline], view[newline + 1:])
            if self._skipping:
                if newline >= 0:
                    self._skipping = False
                continue
            room = MAX_LINE_BYTES - 1 - len(self._buffer)  # content bytes a line may still take before its "\n"
            if len(chunk) > room:
                frames.append(None)
                self._buffer.clear()
                self._skipping = newline < 0
                continue
            self._buffer += chunk
            if newline >= 0:
                line = bytes(self._buffer)
                self._buffer.clear()
                frames.append(line[:-1] if line.endswith(b"\r") else line)
        return frames


class _Client:
    """The client being served: its address and, once it said hello, its name."""

    def __init__(self, peer: str):
        self.peer = peer
        self.name: str | None = None


class _PatchRequestHandler(socketserver.BaseRequestHandler):
    """One connection: the client served, or one told that the server is busy."""

    server: "PatchServer"

    def handle(self) -> None:
        server = self.server
        peer = "%s:%s" % self.client_address[:2]
        me = _Client(peer)
        with server.slot:
            server.slot.wait_for(lambda: server.serving is None or server.closing.is_set(), timeout=BUSY_GRACE_S)
            if server.closing.is_set():
                return
            serving = server.serving
            if serving is None:
                server.serving, server.client_socket = me, self.request
        if serving is not None:
            self._refuse_busy(serving, peer)
            return
        _LOG.info("patch client %s connected", peer)
        try:
            self._serve(me, peer)
        finally:
            server.release(me)

    def _refuse_busy(self, serving: _Client, peer: str) -> None:
        _LOG.info("patch client %s refused: busy with %s", peer, serving.peer)
        try:
            self.request.settimeout(_BUSY_DRAIN_S)
            self.request.sendall(encode_message(busy_reply(serving.peer, serving.name)))
            # Half-close, then read what the client sent until it closes: closing a socket with
            # unread data would reset the connection and could destroy the busy line in transit.
            self.request.shutdown(socket.SHUT_WR)
            while self.request.recv(MAX_LINE_BYTES):
                pass
        except OSError:
            pass

    def _serve(self, me: _Client, peer: str) -> None:
        server = self.server
        framer = LineFramer()
        self.request.settimeout(server.idle_timeout_s)
        while not server.closing.is_set():
            try:
                received = self.request.recv(MAX_LINE_BYTES)
            except socket.timeout:
                _LOG.info("patch client %s silent for %g s; dropping it", peer, server.idle_timeout_s)
                return
            except OSError as error:
                _LOG.info("patch client %s: %s; dropping it", peer, error)
                return
            if not received:
                _LOG.info("patch client %s closed the connection", peer)
                return
            for line in framer.feed(received):
                if line is None:
                    reply, done = server.oversized_reply(), False
                else:
                    reply, done = server.answer(line)
                if done:
                    server.release(me)  # a client that connects right after its bye is not told "busy"
                try:
                    self.request.sendall(encode_message(reply))
                except OSError as error:
                    _LOG.info("patch client %s went away before its reply: %s", peer, error)
                    return
                if done:
                    return


class _NotJson(ValueError):
    pass


def _strict_object(pairs):
    seen = set()
    for key, _ in pairs:
        if key in seen:
            raise _NotJson(f"member {key!r} given twice")
        seen.add(key)
    return dict(pairs)


def _refuse_constant(name):
    raise _NotJson(f"{name} is not JSON")


_MAX_DEPTH = 32  # as the C# core's PatchJson.MaxDepth


def _depth(value, level: int = 1) -> int:
    if isinstance(value, dict):
        return max([level] + [_depth(v, level + 1) for v in value.values()])
    if isinstance(value, list):
        return max([level] + [_depth(v, level + 1) for v in value])
    return level - 1


def _dac_triple(value, field: str) -> list[int]:
    if not isinstance(value, list) or len(value) != 3:
        raise ValueError(f"patch {field} {_json_text(value)} must be three DAC values [r, g, b]")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or v != math.floor(v) or not 0 <= v <= 255:
            raise ValueError(f"patch {field} {_json_text(value)} must be integers 0..255 (8-bit DAC values)")
    return [int(v) for v in value]


def _window(value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value <= 1:
        raise ValueError(f"patch window {_json_text(value)} must be a number in (0, 1] (the fraction of the field)")
    return float(value)


def _eye(request: dict) -> str:
    eye = request.get("eye", "both")
    if not isinstance(eye, str) or eye not in EYES:
        raise ValueError(f'patch eye {_json_text(eye)} must be "left", "right" or "both"')
    return eye


def _log_target(eye: str) -> None:
    _LOG.info("showing the centring target%s", "" if eye == "both" else f" in the {eye} eye")


class PatchServer(socketserver.ThreadingMixIn, socketserver.TCPServer):
    """A patch-protocol server that hands each shown patch to ``present``.

    Parameters
    ----------
    present : callable
        ``present([r, g, b])`` puts the patch on screen and returns once it is
        presented; ``window``/``surround`` and ``eye`` come as keywords, only
        when not the default (module docstring). An exception it raises is
        reported to the client as ``ok: false``.
    host : str
        Address to listen on; loopback by default.
    port : int
        TCP port; 0 picks a free one (see :attr:`address`).
    display_name : str
        What the ``hello`` reply names as the display.
    idle_timeout_s : float
        A client silent this long is dropped. The workbench is silent while the
        CS-2000 measures (up to ~4 min per dark patch, twice with an ND retry)
        and while a run is paused, hence the 10-minute default.
    apl_patches : bool
        Accept the optional ``window`` and ``surround`` fields of ``show``
        (``present`` must then take them as keywords); ``False`` answers them
        as unknown fields, like a server written before they existed.
    eye_field : bool
        Accept the optional ``eye`` field of ``show`` and ``target``; ``False``
        plays a server written before it.
    target_command : bool
        Accept the ``target`` command; ``False`` answers it as an unknown cmd.
    show_target : callable, optional
        ``show_target(eye)`` draws the centring target in ``eye`` (``"both"``,
        ``"left"``, ``"right"``) and returns once it is presented; by default
        the target is logged (this server draws nothing itself).

    Examples
    --------
    >>> from instruments.headset import SimulatedHeadset
    >>> headset = SimulatedHeadset()
    >>> with PatchServer(headset.show) as server:  # doctest: +SKIP
    ...     server.start()
    ...     print(server.address)
    """

    allow_reuse_address = True
    daemon_threads = True
    block_on_close = False

    def __init__(
        self,
        present: Callable[..., None],
        host: str = "127.0.0.1",
        port: int = 0,
        *,
        display_name: str = "reference patch server",
        idle_timeout_s: float = 600.0,
        apl_patches: bool = True,
        eye_field: bool = True,
        target_command: bool = True,
        show_target: Callable[[str], None] | None = None,
    ):
        self.present = present
        self.show_target = show_target or _log_target
        self.apl_patches = bool(apl_patches)
        self.eye_field = bool(eye_field)
        self.target_command = bool(target_command)
        self.display_name = display_name
        self.idle_timeout_s = float(idle_timeout_s)
        self.closing = threading.Event()
        self.slot = threading.Condition()
        self.serving: _Client | None = None
        self.client_socket: socket.socket | None = None
        self._thread: threading.Thread | None = None
        super().__init__((host, port), _PatchRequestHandler)

    @property
    def address(self) -> tuple[str, int]:
        """``(host, port)`` the server listens on."""
        host, port = self.server_address[:2]
        return str(host), int(port)

    @property
    def show_fields(self) -> tuple[str, ...]:
        """The fields this server accepts in ``show``, in the order its errors list them."""
        return ("cmd", "id", "rgb") + (("window", "surround") if self.apl_patches else ()) \
            + (("eye",) if self.eye_field else ())

    @property
    def target_fields(self) -> tuple[str, ...]:
        """The fields this server accepts in ``target``."""
        return ("cmd", "id", "eye") if self.eye_field else ("cmd", "id")

    def release(self, client: _Client) -> None:
        """The client is done: the next connection is served (idempotent)."""
        with self.slot:
            if self.serving is client:
                self.serving = None
            self.slot.notify_all()

    @staticmethod
    def oversized_reply() -> dict:
        """The reply to a line longer than the protocol's limit (the server then skips to its end)."""
        return {"ok": False, "id": None, "error": f"line longer than {MAX_LINE_BYTES} bytes (the protocol's limit, "
                                                  "terminator included); skipped to its end"}

    def answer(self, line: bytes) -> tuple[dict, bool]:
        """The reply to one request line, and whether the connection ends after it."""
        try:
            request = json.loads(line.decode("utf-8"), object_pairs_hook=_strict_object,
                                 parse_constant=_refuse_constant)
            if _depth(request) > _MAX_DEPTH:
                raise _NotJson(f"nested deeper than {_MAX_DEPTH}")
        except (ValueError, UnicodeDecodeError, RecursionError):  # JSONDecodeError and _NotJson are ValueErrors
            return {"ok": False, "id": None, "error": f"not JSON: {line[:_CLIP].decode('utf-8', 'replace')}"}, False
        if not isinstance(request, dict):
            return {"ok": False, "id": None, "error": "a request must be a JSON object"}, False
        request_id = request.get("id")
        if isinstance(request_id, bool) or not isinstance(request_id, int):
            got = _json_text(request_id) if "id" in request else "none"
            return {"ok": False, "id": None, "error": f"a request must carry an integer 'id'; got {got}"}, False
        commands = "hello, show, target or bye" if self.target_command else "hello, show or bye"
        if "cmd" not in request:
            return self._refuse(request_id, f"a request must carry a 'cmd': {commands}"), False
        command = request["cmd"]
        if command == "hello":
            if request.get("protocol") != PATCH_PROTOCOL:
                return {"ok": False, "id": request_id, "protocol": PATCH_PROTOCOL,
                        "error": f"this server speaks {PATCH_PROTOCOL}"}, False
            with self.slot:
                if self.serving is not None and isinstance(request.get("client"), str):
                    self.serving.name = request["client"]
            return {"ok": True, "id": request_id, "protocol": PATCH_PROTOCOL,
                    "display": self.display_name}, False
        if command == "show":
            return self._show(request, request_id), False
        if command == "target" and self.target_command:
            return self._target(request, request_id), False
        if command == "bye":
            return {"ok": True, "id": request_id}, True
        name = f"'{_clip(command)}'" if isinstance(command, str) else _json_text(command)
        return self._refuse(request_id, f"unknown cmd {name}; use {commands}"), False

    @staticmethod
    def _refuse(request_id, error: str) -> dict:
        return {"ok": False, "id": request_id, "error": error}

    @staticmethod
    def _unknown_field(request: dict, command: str, known: tuple[str, ...]) -> str | None:
        unknown = [name for name in request if name not in known]
        if unknown:
            return f"unknown field '{_clip(unknown[0])}' in {command}; this server knows {', '.join(known)}"
        return None

    def _show(self, request: dict, request_id) -> dict:
        unknown = self._unknown_field(request, "show", self.show_fields)
        if unknown:
            return self._refuse(request_id, unknown)
        try:
            rgb = _dac_triple(request.get("rgb"), "rgb")
            window = _window(request["window"]) if "window" in request else 1.0
            surround = _dac_triple(request["surround"], "surround") if "surround" in request else [0, 0, 0]
            eye = _eye(request)
        except ValueError as error:
            return self._refuse(request_id, str(error))
        frame = {}
        if window < 1.0:
            frame.update(window=window, surround=surround)
        if eye != "both":
            frame.update(eye=eye)
        try:
            self.present(rgb, **frame)
        except Exception as error:  # reported to the client, which decides
            _LOG.warning("could not present patch %s: %s", rgb, error)
            return self._refuse(request_id, f"could not present {rgb}: {error}")
        return {"ok": True, "id": request_id}

    def _target(self, request: dict, request_id) -> dict:
        unknown = self._unknown_field(request, "target", self.target_fields)
        if unknown:
            return self._refuse(request_id, unknown)
        try:
            eye = _eye(request)
        except ValueError as error:
            return self._refuse(request_id, str(error))
        try:
            self.show_target(eye)
        except Exception as error:  # reported to the client, which decides
            _LOG.warning("could not present the centring target: %s", error)
            return self._refuse(request_id, f"could not present the centring target: {error}")
        return {"ok": True, "id": request_id}

    def start(self) -> "PatchServer":
        """Serve in a background (daemon) thread; returns ``self``."""
        self._thread = threading.Thread(target=self.serve_forever, kwargs={"poll_interval": _SHUTDOWN_POLL_S},
                                        name="patch-server", daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop serving and release the port."""
        self.closing.set()
        with self.slot:
            self.slot.notify_all()
            client = self.client_socket if self.serving is not None else None
        if client is not None:  # wake a handler waiting for its client's next line
            try:
                client.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        if self._thread is not None:
            self.shutdown()
            self._thread.join()
            self._thread = None
        self.server_close()

    def __exit__(self, *exc):
        self.close()


class _Recorder:
    """``--record FILE``: one JSON line per picture presented, as the C# host writes them."""

    def __init__(self, path: str | None):
        self._file = open(path, "a", encoding="utf-8") if path else None
        self._lock = threading.Lock()

    def write(self, record: dict) -> None:
        if self._file is None:
            return
        with self._lock:
            self._file.write(json.dumps(record, separators=(", ", ": ")) + "\n")
            self._file.flush()


def _run_unity_mono(args) -> int:
    """Replace this process by the Unity package's C# patch server under mono (same options)."""
    from instruments.unity_mono import MonoUnavailable, mono_command

    try:
        command = mono_command("patch-server")
    except MonoUnavailable as error:
        print(f"error: --impl unity-mono: {error}", file=sys.stderr)
        return 2
    command += ["--host", args.host, "--port", str(args.port), "--idle-timeout", repr(float(args.idle_timeout))]
    if args.record:
        command += ["--record", os.path.abspath(args.record)]
    sys.stdout.flush()
    sys.stderr.flush()
    if os.name == "posix":
        os.execv(command[0], command)  # signals (Ctrl-C, terminate) reach the server itself
    import subprocess  # pragma: no cover - not POSIX

    return subprocess.call(command)  # pragma: no cover


def main(argv: list[str] | None = None) -> int:
    """``python -m instruments.patch_server``: serve patches to a simulated headset."""
    parser = argparse.ArgumentParser(
        prog="python -m instruments.patch_server",
        description=f"Reference {PATCH_PROTOCOL} server: shows patches on a simulated headset and logs them.",
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default: loopback)")
    parser.add_argument("--port", type=int, required=True, help="TCP port (0: any free port, printed)")
    parser.add_argument("--idle-timeout", type=float, default=600.0, metavar="S",
                        help="drop a client silent for S seconds (default 600)")
    parser.add_argument("--impl", choices=IMPLEMENTATIONS, default="python",
                        help="python: this reference server on the simulated headset (default); unity-mono: the "
                             "Unity package's C# patch server (VrPatchServer's core) under mono, headless "
                             "(needs mono and mcs: apt-get install mono-mcs mono-runtime)")
    parser.add_argument("--record", metavar="FILE",
                        help="append every picture presented to FILE, one JSON line each")
    args = parser.parse_args(argv)
    if args.impl == "unity-mono":
        return _run_unity_mono(args)

    from instruments.headset import SimulatedHeadset, radiance_to_XYZ

    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    headset = SimulatedHeadset()
    recorder = _Recorder(args.record)

    def present(rgb: list, window: float = 1.0, surround=(0, 0, 0), eye: str = "both") -> None:
        headset.show(rgb, window=window, surround=surround)
        recorder.write({"cmd": "show", "rgb": list(rgb), "window": window, "surround": list(surround), "eye": eye})
        _, Y, _ = radiance_to_XYZ(headset.current_radiance())
        frame = "" if window >= 1 else f" as {window:g} of the field on {list(surround)}"
        panel = "" if eye == "both" else f" in the {eye} eye (the other black)"
        _LOG.info("showing %s%s%s: %.4g cd/m²", rgb, frame, panel, Y)

    def show_target(eye: str) -> None:
        recorder.write({"cmd": "target", "eye": eye})
        _log_target(eye)

    try:
        server = PatchServer(present, args.host, args.port, display_name=headset.describe(),
                             idle_timeout_s=args.idle_timeout, show_target=show_target)
    except OSError as error:
        print(f"error: cannot listen on {args.host}:{args.port} ({error}); choose another --port",
              file=sys.stderr)
        return 2
    host, port = server.address
    print(f"patch server ({PATCH_PROTOCOL}) listening on tcp:{host}:{port}", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
