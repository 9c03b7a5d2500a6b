"""Reference server of the patch protocol (``vr-workbench-patch/1``).

A VR developer can read this module as a model of what the VR application must
do (the protocol itself is documented in :mod:`instruments.patch_display`):
listen on loopback, answer ``hello``, and for every ``show`` put the patch on
the headset and reply only once a frame showing it has been presented.

Here the "headset" is a callable, ``present(rgb)``: the command line forwards
the patches to a :class:`instruments.headset.SimulatedHeadset` and logs what it
emits; tests pass the ``show`` of their own simulated headset. In a game engine
``present`` sets the colour of a full-screen unlit quad in front of both eyes,
waits until the compositor has presented that frame, and returns. An APL patch
(``window`` < 1) is handed over as ``present(rgb, window=w, surround=[r, g, b])``:
the engine fills the field with the surround and draws the patch as a centred
rectangle of the field's aspect ratio whose sides are ``sqrt(w)`` of the
field's. A server built with ``apl_patches=False`` stands for one that does not
know those fields: it refuses them by name, as every server must refuse a
field it does not know.

Run it with::

    python -m instruments.patch_server --port 47800
"""

from __future__ import annotations

import argparse
import json
import logging
import socket
import socketserver
import sys
import threading
from typing import Callable

from instruments.patch_display import (
    PATCH_PROTOCOL,
    SHOW_FIELDS,
    LineReader,
    encode_message,
    validate_patch_rgb,
    validate_patch_window,
)

__all__ = ["PatchServer", "main"]

_LOG = logging.getLogger(__name__)

_SHUTDOWN_POLL_S = 0.05  # how often the serving thread looks for a shutdown request


class _PatchRequestHandler(socketserver.BaseRequestHandler):
    """Serves one client connection: one reply per request line, in order."""

    server: "PatchServer"

    def handle(self) -> None:
        reader = LineReader(self.request)
        peer = "%s:%s" % self.client_address[:2]
        _LOG.info("patch client %s connected", peer)
        self.server.client_socket = self.request
        while not self.server.closing.is_set():
            try:
                line = reader.readline(self.server.idle_timeout_s)
            except TimeoutError:
                _LOG.info("patch client %s silent for %g s; dropping it", peer, self.server.idle_timeout_s)
                return
            except (OSError, ValueError) as error:
                _LOG.info("patch client %s: %s; dropping it", peer, error)
                return
            if line is None:
                _LOG.info("patch client %s closed the connection", peer)
                return
            reply, done = self.server.answer(line)
            try:
                self.request.sendall(encode_message(reply))
            except OSError as error:
                _LOG.info("patch client %s: %s", peer, error)
                return
            if done:
                return


class PatchServer(socketserver.TCPServer):
    """A patch-protocol server that hands each shown patch to ``present``.

    Parameters
    ----------
    present : callable
        ``present([r, g, b])`` puts the patch on screen and returns once it is
        presented; an exception it raises is reported to the client as
        ``ok: false``.
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

    def __init__(
        self,
        present: Callable[[list], None],
        host: str = "127.0.0.1",
        port: int = 0,
        *,
        display_name: str = "reference patch server",
        idle_timeout_s: float = 600.0,
        apl_patches: bool = True,
    ):
        self.present = present
        self.apl_patches = bool(apl_patches)
        self.display_name = display_name
        self.idle_timeout_s = float(idle_timeout_s)
        self.closing = threading.Event()
        self.client_socket: socket.socket | None = None
        self._thread: threading.Thread | None = None
        super().__init__((host, port), _PatchRequestHandler)

    @property
    def address(self) -> tuple[str, int]:
        """``(host, port)`` the server listens on."""
        host, port = self.server_address[:2]
        return str(host), int(port)

    def answer(self, line: bytes) -> tuple[dict, bool]:
        """The reply to one request line, and whether the connection ends after it."""
        try:
            request = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError):
            return {"ok": False, "id": None, "error": f"not JSON: {line[:80]!r}"}, False
        if not isinstance(request, dict):
            return {"ok": False, "id": None, "error": "a request must be a JSON object"}, False
        request_id, command = request.get("id"), request.get("cmd")
        if command == "hello":
            if request.get("protocol") != PATCH_PROTOCOL:
                return {"ok": False, "id": request_id, "protocol": PATCH_PROTOCOL,
                        "error": f"this server speaks {PATCH_PROTOCOL}"}, False
            return {"ok": True, "id": request_id, "protocol": PATCH_PROTOCOL,
                    "display": self.display_name}, False
        if command == "show":
            known = SHOW_FIELDS if self.apl_patches else ("cmd", "id", "rgb")
            unknown = [name for name in request if name not in known]
            if unknown:
                return {"ok": False, "id": request_id,
                        "error": f"unknown field {unknown[0]!r} in show; this server knows {', '.join(known)}"}, False
            try:
                rgb = validate_patch_rgb(request.get("rgb"))
                window = validate_patch_window(request.get("window", 1.0))
                surround = validate_patch_rgb(request.get("surround", [0, 0, 0]))
            except ValueError as error:
                return {"ok": False, "id": request_id, "error": str(error)}, False
            try:
                if window < 1.0:
                    self.present(rgb, window=window, surround=surround)
                else:
                    self.present(rgb)
            except Exception as error:  # reported to the client, which decides
                _LOG.warning("could not present patch %s: %s", rgb, error)
                return {"ok": False, "id": request_id, "error": f"could not present {rgb}: {error}"}, False
            return {"ok": True, "id": request_id}, False
        if command == "bye":
            return {"ok": True, "id": request_id}, True
        return {"ok": False, "id": request_id,
                "error": f"unknown cmd {command!r}; use hello, show or bye"}, False

    def start(self) -> "PatchServer":
        """Serve in a background (daemon) thread; returns ``self``."""
        self._thread = threading.Thread(target=self.serve_forever, kwargs={"poll_interval": _SHUTDOWN_POLL_S},
                                        name="patch-server", daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop serving and release the port."""
        self.closing.set()
        if self.client_socket is not None:  # wake a handler waiting for its client's next line
            try:
                self.client_socket.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        if self._thread is not None:
            self.shutdown()
            self._thread.join()
            self._thread = None
        self.server_close()

    def __exit__(self, *exc):
        self.close()


def main(argv: list[str] | None = None) -> int:
    """``python -m instruments.patch_server``: serve patches to a simulated headset."""
    from instruments.headset import SimulatedHeadset, radiance_to_XYZ

    parser = argparse.ArgumentParser(
        prog="python -m instruments.patch_server",
        description=f"Reference {PATCH_PROTOCOL} server: shows patches on a simulated headset and logs them.",
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default: loopback)")
    parser.add_argument("--port", type=int, required=True, help="TCP port (0: any free port, printed)")
    parser.add_argument("--idle-timeout", type=float, default=600.0, metavar="S",
                        help="drop a client silent for S seconds (default 600)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    headset = SimulatedHeadset()

    def present(rgb: list, window: float = 1.0, surround=(0, 0, 0)) -> None:
        headset.show(rgb, window=window, surround=surround)
        _, Y, _ = radiance_to_XYZ(headset.current_radiance())
        frame = "" if window >= 1 else f" as {window:g} of the field on {list(surround)}"
        _LOG.info("showing %s%s: %.4g cd/m²", rgb, frame, Y)

    try:
        server = PatchServer(present, args.host, args.port, display_name=headset.describe(),
                             idle_timeout_s=args.idle_timeout)
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
