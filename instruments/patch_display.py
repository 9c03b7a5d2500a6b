"""Patch displays: where the measurement sequence puts its colour patches.

A patch display shows one patch of 8-bit DAC values at a time
(:class:`PatchDisplay`): full field, or as a centred window on a surround
(an APL patch, for displays whose output depends on the rest of the picture). Three are here: the simulated headset
(:class:`SimulatedPatchDisplay`), a VR application reached over TCP
(:class:`TcpPatchDisplay`), and a mirror that shows each patch on several
displays (:class:`MirroredPatchDisplay`). The full-screen Qt window lives in
``workbench.gui``.

The patch protocol (``vr-workbench-patch/1``)
---------------------------------------------
A VR application implements this small protocol so that the workbench can show
calibration patches in the headset. :mod:`instruments.patch_server` is a
complete reference server to read as a model.

Transport
    TCP. The VR application is the **server** and listens on loopback
    (``127.0.0.1``) unless told otherwise; the workbench is the **client**.
Framing
    One JSON object per line, UTF-8, ended by ``\\n`` (``\\r\\n`` accepted), at
    most :data:`MAX_LINE_BYTES` bytes. Every request carries an integer ``id``;
    the server answers every request with exactly one reply carrying the same
    ``id``, in order.
Requests and replies
    ``{"cmd": "hello", "id": 1, "protocol": "vr-workbench-patch/1", "client": "vr-workbench 0.1.0"}``
        → ``{"ok": true, "id": 1, "protocol": "vr-workbench-patch/1", "display": "<what shows the patches>"}``.
        The client sends it first; a server that speaks another version answers
        ``ok: false``.
    ``{"cmd": "show", "id": 2, "rgb": [255, 128, 0]}``
        → ``{"ok": true, "id": 2}`` **once a frame showing the patch has been
        presented**: the whole field of view of both eyes, these exact integer
        values 0..255 written to the frame buffer (no tone mapping, no
        post-processing, no sRGB encoding by the engine, no dithering).
    ``{"cmd": "show", "id": 3, "rgb": [255, 255, 255], "window": 0.1, "surround": [64, 64, 64]}``
        → ``{"ok": true, "id": 3}``: an **APL patch**. Optional fields:
        ``window``, a number in (0, 1], the fraction of the field of view the
        patch covers (a centred rectangle of the field's aspect ratio, its
        sides scaled by ``sqrt(window)``, the same in both eyes; the instrument
        aims at its centre), default 1 (full field); ``surround``, three
        integers 0..255, the DAC values of the rest of the field, default
        ``[0, 0, 0]``. The client sends them only for a patch that is not full
        field.
    ``{"cmd": "show", "id": 4, "rgb": [255, 0, 0], "eye": "left"}``
        → ``{"ok": true, "id": 4}``: a patch in **one eye**. Optional field
        ``eye``: ``"left"``, ``"right"`` or ``"both"`` (default both); the
        named eye's panel shows the patch (with ``window``/``surround`` as
        usual), the other eye's panel is black. The client sends it only when
        it is not ``"both"`` (``measure --eye left|right``); a server written
        before it refuses the unknown field, and the client reports that the
        display cannot show a patch to one eye (:class:`EyeUnsupported`).
    ``{"cmd": "target", "id": 5}`` (optional ``eye`` as above)
        → ``{"ok": true, "id": 5}`` once a frame showing the **centring
        target** has been presented: a black field with concentric white
        rings at 10, 20, 30 and 40 % of the field's smaller side in radius
        (2-pixel lines) and a cross through the centre, to aim the instrument
        through the lens (``measure --target``). It stays until the next
        ``show``. A server without it answers the unknown-``cmd`` error
        (:class:`TargetUnsupported`).
    ``{"cmd": "bye", "id": 3}``
        → ``{"ok": true, "id": 3}``; then the server closes the connection (and
        may go back to its own picture).
Errors
    ``{"ok": false, "id": N, "error": "<what was wrong>"}`` for an unknown
    ``cmd``, a malformed ``rgb``, ``window`` or ``surround``, a field the
    server does not know (the error names it: ``unknown field 'window'``),
    or a patch that could not be shown; a line that is not JSON gets
    ``"id": null``. The connection stays open. One client at a time: while a
    client is connected, a second connection gets one line
    ``{"ok": false, "id": null, "error": "busy: ..."}`` naming the first
    client, and is closed. A server that cannot show APL
    patches answers such a ``show`` with ``ok: false`` naming the field, and
    the client reports that the display cannot show APL patches
    (:class:`AplPatchesUnsupported`).
Timeouts
    The client waits at most ``timeout_s`` to connect and for each reply, then
    reports which request went unanswered; the server drops a client that has
    been silent for its idle timeout. A client whose connection was dropped
    (e.g. during a long pause) connects again, says ``hello`` again, and
    repeats its ``show`` (once; showing a patch twice is harmless).

Examples
--------
A session as it appears on the wire (``>`` client, ``<`` server)::

    > {"cmd": "hello", "id": 1, "protocol": "vr-workbench-patch/1", "client": "vr-workbench 0.1.0"}
    < {"ok": true, "id": 1, "protocol": "vr-workbench-patch/1", "display": "Unity 2022.3 on HTC Vive"}
    > {"cmd": "show", "id": 2, "rgb": [0, 0, 0]}
    < {"ok": true, "id": 2}
    > {"cmd": "bye", "id": 3}
    < {"ok": true, "id": 3}
"""

from __future__ import annotations

import json
import logging
import socket
import time
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = [
    "PATCH_PROTOCOL",
    "MAX_LINE_BYTES",
    "PatchDisplay",
    "PatchDisplayError",
    "SimulatedPatchDisplay",
    "MirroredPatchDisplay",
    "TcpPatchDisplay",
    "validate_patch_rgb",
    "validate_patch_window",
    "AplPatchesUnsupported",
    "SHOW_FIELDS",
    "encode_message",
    "is_apl_patch",
    "show_patch",
    "LineReader",
    "EYES",
    "validate_eye",
    "EyeUnsupported",
    "TargetUnsupported",
    "show_target",
]

_LOG = logging.getLogger(__name__)

PATCH_PROTOCOL = "vr-workbench-patch/1"
"""Name and version of the line-based JSON patch protocol."""

MAX_LINE_BYTES = 4096
"""Longest line either side may send, terminator included."""


class PatchDisplayError(RuntimeError):
    """A patch could not be shown; the message names the display, the request and the fix."""


class AplPatchesUnsupported(PatchDisplayError):
    """The display cannot show a patch as a window on a surround (an APL patch)."""


class EyeUnsupported(PatchDisplayError):
    """The display cannot show a patch to one eye only (its patch server predates ``eye``)."""


class TargetUnsupported(PatchDisplayError):
    """The display cannot show the centring target (its patch server predates ``target``)."""


SHOW_FIELDS = ("cmd", "id", "rgb", "window", "surround")
"""Fields a ``show`` request may carry (and ``eye``, of the protocol's per-eye addition); a server
answers any other with ``ok: false`` naming it."""

EYES = ("both", "left", "right")
"""Which panel of the headset shows the patch (``eye`` of ``show`` and ``target``); the other one is black."""


def validate_eye(eye) -> str:
    """Return ``eye`` if it is one of :data:`EYES`, or raise ``ValueError`` naming it and the choices."""
    if not isinstance(eye, str) or eye not in EYES:
        raise ValueError(f"eye {eye!r} must be one of {', '.join(EYES)}")
    return eye


class _ConnectionDropped(PatchDisplayError):
    """The patch server closed (or reset) the connection."""


class _Refused(PatchDisplayError):
    """The patch server answered ``ok: false``; ``server_error`` is its reason."""

    def __init__(self, message: str, server_error: str):
        super().__init__(message)
        self.server_error = server_error


@runtime_checkable
class PatchDisplay(Protocol):
    """Something that shows one patch of DAC values at a time, and names itself.

    ``show`` takes ``window`` and ``surround`` only for APL patches (a patch
    that is not full field), so a display that shows full-field patches only
    may take ``rgb_dac`` alone.
    """

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        """Show the patch ``rgb_dac`` (three integers 0..255) as ``window`` of the field on
        ``surround``; return once it is on screen."""

    def close(self) -> None:
        """Release the display (idempotent)."""

    def describe(self) -> str:
        """One line naming what shows the patches, for the journal header."""


def validate_patch_rgb(rgb_dac) -> list[int]:
    """Return ``rgb_dac`` as three ints 0..255, or raise ``ValueError`` naming the bad value."""
    values = np.asarray(rgb_dac)
    if values.shape != (3,):
        raise ValueError(f"patch rgb {rgb_dac!r} must be three DAC values [r, g, b]")
    try:
        as_float = values.astype(float)
    except (TypeError, ValueError):
        raise ValueError(f"patch rgb {rgb_dac!r} must be numbers 0..255") from None
    if not np.all(np.isfinite(as_float)) or np.any(as_float != np.round(as_float)) \
            or np.any((as_float < 0) | (as_float > 255)):
        raise ValueError(f"patch rgb {rgb_dac!r} must be integers 0..255 (8-bit DAC values)")
    return [int(v) for v in as_float]


def validate_patch_window(window) -> float:
    """Return ``window`` as a float in (0, 1], or raise ``ValueError`` naming the bad value."""
    try:
        value = float(window)
    except (TypeError, ValueError):
        raise ValueError(f"patch window {window!r} must be a number in (0, 1]") from None
    if isinstance(window, bool) or not np.isfinite(value) or not 0 < value <= 1:
        raise ValueError(f"patch window {window!r} must be a number in (0, 1] (the fraction of the field)")
    return value


def is_apl_patch(window: float = 1.0, surround=(0, 0, 0)) -> bool:
    """Whether a patch is an APL patch (not full field); a surround behind a full field is invisible."""
    return validate_patch_window(window) < 1.0


def show_patch(display, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
    """``display.show`` with ``window``/``surround`` passed only for an APL patch.

    So that displays which show full-field patches only (``show(rgb)``) keep
    working for every plan without APL patches.
    """
    if not is_apl_patch(window, surround):
        display.show(rgb_dac)
        return
    try:
        display.show(rgb_dac, window=window, surround=surround)
    except TypeError as error:
        if "window" not in str(error) and "surround" not in str(error):
            raise
        describe = getattr(display, "describe", lambda: type(display).__name__)
        raise AplPatchesUnsupported(
            f"{describe()} cannot show APL patches (a patch as a window on a surround): its show() takes "
            "no 'window' or 'surround'; show the patches in the full-screen window or a VR application "
            "whose patch server accepts them, or measure a plan without APL patches (e.g. --plan paper)"
        ) from error


def show_target(display, eye: str = "both") -> None:
    """Show the centring target on ``display`` (``display.target(eye)``); return once it is shown.

    Raises
    ------
    TargetUnsupported
        If the display has no centring target (no ``target`` method, or its
        server refused the command).
    """
    eye = validate_eye(eye)
    target = getattr(display, "target", None)
    if target is None:
        describe = getattr(display, "describe", lambda: type(display).__name__)
        raise TargetUnsupported(f"{describe()} has no centring target; aim the instrument at the centre of "
                                "a white patch instead, or show the patches where a target can be drawn "
                                "(--display window or tcp:HOST:PORT)")
    target(eye)


def encode_message(message: dict) -> bytes:
    """One protocol line: JSON, UTF-8, ``\\n``-terminated."""
    line = json.dumps(message, separators=(", ", ": ")).encode("utf-8") + b"\n"
    if len(line) > MAX_LINE_BYTES:
        raise ValueError(f"message of {len(line)} bytes exceeds the protocol's {MAX_LINE_BYTES}-byte line limit")
    return line


class LineReader:
    """Reads ``\\n``-terminated lines from a socket, each with a deadline.

    Parameters
    ----------
    sock : socket.socket
        A connected socket; its timeout is changed by :meth:`readline`.
    """

    def __init__(self, sock: socket.socket):
        self._sock = sock
        self._buffer = bytearray()

    def readline(self, timeout_s: float) -> bytes | None:
        """The next line without its terminator, or ``None`` once the peer has closed.

        Raises
        ------
        TimeoutError
            If no complete line arrives within ``timeout_s`` seconds.
        ValueError
            If a line exceeds :data:`MAX_LINE_BYTES`.
        """
        deadline = time.monotonic() + timeout_s
        while b"\n" not in self._buffer:
            if len(self._buffer) > MAX_LINE_BYTES:
                raise ValueError(f"line longer than {MAX_LINE_BYTES} bytes")
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError(f"no complete line within {timeout_s:g} s")
            self._sock.settimeout(remaining)
            try:
                chunk = self._sock.recv(MAX_LINE_BYTES)
            except socket.timeout:
                raise TimeoutError(f"no complete line within {timeout_s:g} s") from None
            if not chunk:
                return None
            self._buffer += chunk
        line, _, rest = bytes(self._buffer).partition(b"\n")
        self._buffer = bytearray(rest)
        return line.rstrip(b"\r")


class SimulatedPatchDisplay:
    """Shows patches on a :class:`instruments.headset.SimulatedHeadset` (instantly).

    Parameters
    ----------
    headset : SimulatedHeadset
        Anything with ``show(rgb_dac)`` and ``describe()``.
    """

    def __init__(self, headset):
        self.headset = headset

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        """Put ``rgb_dac`` on the simulated headset (at once), as ``window`` on ``surround``."""
        rgb = validate_patch_rgb(rgb_dac)
        if is_apl_patch(window, surround):
            self.headset.show(rgb, window=validate_patch_window(window), surround=validate_patch_rgb(surround))
        else:
            self.headset.show(rgb)

    def close(self) -> None:
        """Nothing to release."""

    def describe(self) -> str:
        """One line naming the display, for journals."""
        return self.headset.describe()


class MirroredPatchDisplay:
    """Shows every patch on several displays, in order (e.g. a VR app and the simulated headset).

    Parameters
    ----------
    *displays : PatchDisplay
    """

    def __init__(self, *displays: PatchDisplay):
        if not displays:
            raise ValueError("MirroredPatchDisplay needs at least one display")
        self.displays = displays

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        """Show ``rgb_dac`` (as ``window`` on ``surround``) on each display in turn."""
        for display in self.displays:
            show_patch(display, rgb_dac, window, surround)

    def target(self, eye: str = "both") -> None:
        """Show the centring target on each display that has one (at least one must)."""
        shown = [display for display in self.displays if getattr(display, "target", None) is not None]
        if not shown:
            show_target(self.displays[0], eye)  # raises, naming the display
        for display in shown:
            display.target(eye)

    def close(self) -> None:
        """Close every display."""
        for display in self.displays:
            display.close()

    def describe(self) -> str:
        """The displays' descriptions joined by ``+``."""
        return " + ".join(display.describe() for display in self.displays)


class TcpPatchDisplay:
    """Client of the patch protocol: shows patches in a VR application over TCP.

    Parameters
    ----------
    host : str
        Where the VR application listens (normally loopback, ``127.0.0.1``).
    port : int
        Its TCP port.
    timeout_s : float
        Longest wait to connect and for each reply, in seconds.
    client : str
        How the client introduces itself in ``hello``.
    eye : str
        Which panel shows the patches (:data:`EYES`): ``"both"`` (the default;
        ``eye`` is then not sent, so the wire is as before the per-eye
        addition), ``"left"`` or ``"right"`` (sent in every ``show`` and ``target``).

    Raises
    ------
    PatchDisplayError
        If the application cannot be reached, does not answer ``hello`` in
        time, or speaks another protocol version.

    Examples
    --------
    >>> with TcpPatchDisplay("127.0.0.1", 47800) as display:  # doctest: +SKIP
    ...     display.show([255, 255, 255])
    """

    def __init__(self, host: str, port: int, timeout_s: float = 5.0, *, client: str = "instruments",
                 eye: str = "both"):
        if not (timeout_s > 0):
            raise ValueError(f"timeout_s {timeout_s!r} must be a positive number of seconds")
        self.host, self.port, self.timeout_s = host, int(port), float(timeout_s)
        self.client = client
        self.eye = validate_eye(eye)
        self._next_id = 1
        self._sock: socket.socket | None = None
        self._closed = False
        self.display_name = ""
        self._connect()

    def _connect(self) -> None:
        """Connect and say ``hello``; on failure nothing stays open."""
        try:
            sock = socket.create_connection((self.host, self.port), timeout=self.timeout_s)
        except OSError as error:
            raise PatchDisplayError(
                f"cannot connect to the patch server at {self.where} ({error}); start the VR application's "
                "patch server (or `python -m instruments.patch_server --port PORT`) and check host and port"
            ) from error
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock, self._reader = sock, LineReader(sock)
        try:
            reply = self._request({"cmd": "hello", "protocol": PATCH_PROTOCOL, "client": self.client})
            if reply.get("protocol") != PATCH_PROTOCOL:
                raise PatchDisplayError(
                    f"the patch server at {self.where} speaks {reply.get('protocol')!r}, not "
                    f"{PATCH_PROTOCOL!r}; update the VR application's patch server"
                )
        except BaseException:
            sock.close()
            self._sock = None
            raise
        self.display_name = str(reply.get("display", ""))

    @property
    def where(self) -> str:
        """``tcp:HOST:PORT``, as ``--display`` spells it."""
        return f"tcp:{self.host}:{self.port}"

    def _request(self, message: dict) -> dict:
        message = {**message, "id": self._next_id}
        self._next_id += 1
        _LOG.debug("patch %s > %s", self.where, message)
        try:
            self._sock.sendall(encode_message(message))
            line = self._reader.readline(self.timeout_s)
        except TimeoutError:
            raise PatchDisplayError(
                f"the patch server at {self.where} did not answer {message['cmd']!r} (id {message['id']}) "
                f"within {self.timeout_s:g} s; check that the VR application is running and presenting frames"
            ) from None
        except OSError as error:  # reset, broken pipe: the server is gone or dropped us
            raise _ConnectionDropped(
                f"the connection to the patch server at {self.where} failed during {message['cmd']!r} "
                f"(id {message['id']}): {error}; restart the VR application and resume"
            ) from error
        except ValueError as error:
            raise PatchDisplayError(
                f"the patch server at {self.where} sent a line longer than {MAX_LINE_BYTES} bytes during "
                f"{message['cmd']!r} (id {message['id']}): {error}; it must follow {PATCH_PROTOCOL}"
            ) from error
        if line is None:
            raise _ConnectionDropped(
                f"the patch server at {self.where} closed the connection during {message['cmd']!r} "
                f"(id {message['id']}); restart the VR application and resume"
            )
        _LOG.debug("patch %s < %s", self.where, line)
        try:
            reply = json.loads(line)
        except json.JSONDecodeError:
            raise PatchDisplayError(
                f"the patch server at {self.where} answered {line[:80]!r}, which is not JSON; "
                f"it must follow {PATCH_PROTOCOL} (see instruments.patch_display)"
            ) from None
        if (isinstance(reply, dict) and reply.get("id") is None and reply.get("ok") is False
                and str(reply.get("error", "")).startswith("busy:")):
            raise PatchDisplayError(
                f"the patch server at {self.where} turned this connection away with {reply['error']!r}"
            )
        if not isinstance(reply, dict) or reply.get("id") != message["id"]:
            raise PatchDisplayError(
                f"the patch server at {self.where} answered {reply!r} to request id {message['id']}; "
                f"replies must carry the request's id, in order ({PATCH_PROTOCOL})"
            )
        if reply.get("ok") is not True:
            reason = str(reply.get("error", "no reason given"))
            raise _Refused(
                f"the patch server at {self.where} refused {message['cmd']!r} {message.get('rgb', '')}: "
                f"{reason}", reason
            )
        return reply

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        """Show ``rgb_dac`` and return once the server says the frame is presented.

        An APL patch (``window`` < 1) is sent with the optional ``window`` and
        ``surround`` fields; a full-field patch without them, exactly as before.
        If the server has dropped the connection (its idle timeout passed while
        the instrument measured or the run was paused), connect again, say
        ``hello`` again and repeat the ``show``, once.

        With :attr:`eye` left or right, the request carries ``eye``.

        Raises
        ------
        AplPatchesUnsupported
            When the server refuses an APL patch naming ``window`` or ``surround``.
        EyeUnsupported
            When the server refuses the ``eye`` field (it predates the per-eye addition).
        """
        request = {"cmd": "show", "rgb": validate_patch_rgb(rgb_dac)}
        if is_apl_patch(window, surround):
            request.update(window=validate_patch_window(window), surround=validate_patch_rgb(surround))
            try:
                self._show(self._with_eye(request))
            except _Refused as error:
                if not any(field in error.server_error for field in ("window", "surround")):
                    raise
                raise AplPatchesUnsupported(
                    f"the display at {self.where} cannot show APL patches (a patch as a window on a "
                    f"surround): {error}. Update the VR application's patch server to accept the optional "
                    f"'window' and 'surround' fields of {PATCH_PROTOCOL} (see the README), or measure a "
                    "plan without APL patches (e.g. --plan paper)"
                ) from error
            return
        self._show(self._with_eye(request))

    def target(self, eye: str | None = None) -> None:
        """Show the centring target (the ``target`` command) in :attr:`eye` (or ``eye``); return once presented.

        Raises
        ------
        TargetUnsupported
            When the server does not know the ``target`` command.
        EyeUnsupported
            When the server refuses the ``eye`` field.
        """
        eye = self.eye if eye is None else validate_eye(eye)
        request = {"cmd": "target", **({"eye": eye} if eye != "both" else {})}
        try:
            self._show(request)
        except _Refused as error:
            if "unknown cmd" not in error.server_error and "'target'" not in error.server_error:
                raise
            raise TargetUnsupported(
                f"the display at {self.where} cannot show the centring target ({error.server_error}); "
                f"update the VR application's patch server to the 'target' command of {PATCH_PROTOCOL}, "
                "or aim the instrument without --target (at the centre of a white patch)"
            ) from error

    def _with_eye(self, request: dict) -> dict:
        """``request`` with ``eye`` when :attr:`eye` is not both (a server that does not know it: :meth:`_show`)."""
        return {**request, "eye": self.eye} if self.eye != "both" else request

    def _show(self, request: dict) -> None:
        try:
            self._request_again_if_dropped(request)
        except _Refused as error:
            if "eye" in request and "'eye'" in error.server_error:
                raise EyeUnsupported(
                    f"the display at {self.where} cannot show a patch to one eye ({error.server_error}); "
                    "update the VR application's patch server, or measure with --eye both"
                ) from error
            raise

    def _request_again_if_dropped(self, request: dict) -> None:
        if self._closed:
            raise PatchDisplayError(f"the patch display {self.where} has been closed")
        if self._sock is None:  # an earlier reconnection failed: try again
            self._connect()
        try:
            self._request(request)
        except _ConnectionDropped as error:
            _LOG.info("patch server %s dropped the connection (%s); connecting again", self.where, error)
            self._sock.close()
            self._sock = None
            self._connect()
            self._request(request)

    def close(self) -> None:
        """Say ``bye`` (best effort) and close the connection."""
        self._closed = True
        if self._sock is None:
            return
        try:
            self._request({"cmd": "bye"})
        except PatchDisplayError as error:
            _LOG.info("patch server %s: %s", self.where, error)
        finally:
            self._sock.close()
            self._sock = None

    def describe(self) -> str:
        """What the server says it shows the patches on, and where it is."""
        return f"{self.display_name or 'VR application'} via {self.where}"

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
