"""Patch displays that speak the seed authors' engine conventions (no acknowledgement protocol).

The seed paper's authors published their 2024 characterization set-up
(Díaz-Barrancas et al., Opt. Express 32:22388, 2024; MATLAB driving a
CS-2000A; ``src/ConnectionUnity.m`` and ``src/ConnectionUnreal.m`` of
github.com/rkl-gilro/ColorCharacterization). A lab that already has their
Unity or Unreal project can calibrate with it through these two displays,
byte for byte as the authors' MATLAB talks to it:

``rgb-text`` (:class:`RgbTextPatchDisplay`), their **Unity** convention
    For each patch the client opens a TCP connection (the engine listens on
    port 55001), writes the bare text ``R,G,B`` (decimal integers 0..255,
    e.g. ``255,0,0``; no line terminator), closes the connection, and waits
    a fixed settle time (2 s in their scripts: ``pause(2)``) before the
    instrument measures. The engine sends nothing back: that the patch is on
    the panel is a guess, right only if the engine shows it within the
    settle time.

``value-shot`` (:class:`ValueShotPatchDisplay`), their **Unreal** convention
    The client holds one connection (the engine listens on port 8890) and
    writes ``Value:r,g,b`` with each channel as DAC/255 in decimal, as
    MATLAB's string concatenation formats a double (``"Value:" + 5/255``
    gives ``Value:0.019608``: five significant digits, ``%.5g``, and ``0``
    and ``1`` as such); no terminator. The engine answers ``SHOT`` (no
    terminator either) once the patch is shown; until the client has read
    ``SHOT`` it sends the value again (their ``while ~strcmp(a, "SHOT")``
    loop), here every :data:`VALUE_SHOT_RESEND_S` seconds, and it gives up
    after a deadline with an error naming the address. At the end of a
    session their script writes ``DONE:0``; :meth:`ValueShotPatchDisplay.close`
    does too.

Neither convention can show an APL patch (a window on a surround), a patch
to one eye, or a centring target, and neither reports an error: what
``vr-workbench-patch/1`` (:mod:`instruments.patch_display`) adds. The
displays here show full-field patches only (their ``show`` takes no
``window``, so :func:`~instruments.patch_display.show_patch` reports an APL
patch as :class:`~instruments.patch_display.AplPatchesUnsupported`).
"""

from __future__ import annotations

import logging
import socket
import time
from typing import Callable

from instruments.patch_display import PatchDisplayError, validate_patch_rgb

__all__ = [
    "RGB_TEXT_DEFAULT_SETTLE_S",
    "VALUE_SHOT_RESEND_S",
    "VALUE_SHOT_ACK",
    "VALUE_SHOT_DONE",
    "rgb_text_message",
    "value_shot_message",
    "matlab_number",
    "RgbTextPatchDisplay",
    "ValueShotPatchDisplay",
]

_LOG = logging.getLogger(__name__)

RGB_TEXT_DEFAULT_SETTLE_S = 2.0
"""Seconds the authors' Unity scripts wait after sending a patch before measuring (``pause(2)``)."""

VALUE_SHOT_RESEND_S = 1.0
"""Seconds :class:`ValueShotPatchDisplay` waits for ``SHOT`` before it sends the value again."""

VALUE_SHOT_ACK = b"SHOT"
"""What the authors' Unreal engine answers once the patch is shown."""

VALUE_SHOT_DONE = b"DONE:0"
"""What the authors' Unreal script writes when the session ends."""

_RECEIVE_BYTES = 4096
_MAX_PENDING_BYTES = 65536  # what an engine may send that is not SHOT before the client gives up


def rgb_text_message(rgb_dac) -> bytes:
    """``b"R,G,B"``: the authors' Unity message for a patch (decimal integers, no terminator).

    Examples
    --------
    >>> rgb_text_message([255, 0, 0])
    b'255,0,0'
    """
    return ",".join(str(v) for v in validate_patch_rgb(rgb_dac)).encode("ascii")


def matlab_number(value: float) -> str:
    """A double as MATLAB's ``string`` (``"text" + x``) writes it for 0 <= x <= 1: ``%.5g``.

    Five significant digits, no trailing zeros, no exponent in this range
    (the smallest non-zero channel, 1/255, is ``0.0039216``).

    Examples
    --------
    >>> matlab_number(5 / 255), matlab_number(0.0), matlab_number(1.0), matlab_number(128 / 255)
    ('0.019608', '0', '1', '0.50196')
    """
    return f"{float(value):.5g}"


def value_shot_message(rgb_dac) -> bytes:
    """``b"Value:r,g,b"``: the authors' Unreal message (each channel DAC/255, :func:`matlab_number`).

    Examples
    --------
    >>> value_shot_message([5, 0, 255])
    b'Value:0.019608,0,1'
    """
    return ("Value:" + ",".join(matlab_number(v / 255) for v in validate_patch_rgb(rgb_dac))).encode("ascii")


class RgbTextPatchDisplay:
    """The authors' Unity convention: one connection per patch, ``R,G,B``, then a settle time.

    Parameters
    ----------
    host, port : str, int
        Where the engine listens (their projects: ``127.0.0.1:55001``).
    settle_s : float
        Seconds to wait after the connection is closed before :meth:`show`
        returns (the instrument measures then); the engine's only
        "acknowledgement". Default :data:`RGB_TEXT_DEFAULT_SETTLE_S`.
    timeout_s : float
        Longest wait to connect and to write.
    sleep : callable
        ``sleep(seconds)``; :func:`time.sleep` by default.
    """

    kind = "rgb-text"

    def __init__(self, host: str, port: int, settle_s: float = RGB_TEXT_DEFAULT_SETTLE_S,
                 timeout_s: float = 5.0, *, sleep: Callable[[float], None] = time.sleep):
        if not settle_s >= 0:
            raise ValueError(f"settle_s {settle_s!r} must be zero or a positive number of seconds")
        if not timeout_s > 0:
            raise ValueError(f"timeout_s {timeout_s!r} must be a positive number of seconds")
        self.host, self.port = host, int(port)
        self.settle_s, self.timeout_s = float(settle_s), float(timeout_s)
        self._sleep = sleep

    @property
    def where(self) -> str:
        """``rgb-text:HOST:PORT:SETTLE_S``, as ``--display`` spells it."""
        return f"rgb-text:{self.host}:{self.port}:{self.settle_s:g}"

    def show(self, rgb_dac) -> None:
        """Send ``R,G,B`` on a new connection, close it, wait :attr:`settle_s`.

        Raises
        ------
        PatchDisplayError
            If the engine cannot be reached (refused, timed out) or the connection
            fails while writing; the message names the address.
        """
        message = rgb_text_message(rgb_dac)
        try:
            with socket.create_connection((self.host, self.port), timeout=self.timeout_s) as sock:
                sock.sendall(message)
                _LOG.debug("patch %s > %r", self.where, message)
        except OSError as error:
            raise PatchDisplayError(
                f"cannot send {message.decode()} to the engine at {self.where} ({error}); start the Unity "
                f"project that listens there (the authors' projects use port 55001) and check host and port"
            ) from error
        self._sleep(self.settle_s)

    def close(self) -> None:
        """Nothing to release: every patch had its own connection."""

    def describe(self) -> str:
        """The convention and the address, for the journal header."""
        return (f"engine via {self.where} (the authors' Unity convention: R,G,B text, no acknowledgement, "
                f"{self.settle_s:g} s settle)")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class ValueShotPatchDisplay:
    """The authors' Unreal convention: ``Value:r,g,b`` on one connection until the engine says ``SHOT``.

    Parameters
    ----------
    host, port : str, int
        Where the engine listens (their projects: ``127.0.0.1:8890``).
    timeout_s : float
        Longest wait to connect, and for ``SHOT`` after the first send of a patch.
    resend_s : float
        Seconds without ``SHOT`` after which the value is sent again
        (default :data:`VALUE_SHOT_RESEND_S`).

    Raises
    ------
    PatchDisplayError
        If the engine cannot be reached; the message names the address.

    Notes
    -----
    The engine may answer every send, so a ``SHOT`` for a value sent again
    can arrive after the patch was acknowledged. Before the first send of
    each patch, whatever the engine has sent since is read and dropped, so
    that a late ``SHOT`` is not taken for the next patch's; one arriving in
    the instant between that and the engine's reply cannot be told apart
    (the convention has no ids), which is why :data:`VALUE_SHOT_RESEND_S`
    is long against an engine's frame time.
    """

    kind = "value-shot"

    def __init__(self, host: str, port: int, timeout_s: float = 10.0, resend_s: float = VALUE_SHOT_RESEND_S):
        if not timeout_s > 0 or not resend_s > 0:
            raise ValueError(f"timeout_s {timeout_s!r} and resend_s {resend_s!r} must be positive seconds")
        self.host, self.port = host, int(port)
        self.timeout_s, self.resend_s = float(timeout_s), float(resend_s)
        self.sends = 0
        """Messages written so far (re-sends included)."""
        self._closed = False
        try:
            self._sock = socket.create_connection((self.host, self.port), timeout=self.timeout_s)
        except OSError as error:
            raise PatchDisplayError(
                f"cannot connect to the engine at {self.where} ({error}); start the Unreal project that "
                "listens there (the authors' projects use port 8890) and check host and port"
            ) from error
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    @property
    def where(self) -> str:
        """``value-shot:HOST:PORT``, as ``--display`` spells it."""
        return f"value-shot:{self.host}:{self.port}"

    def show(self, rgb_dac) -> None:
        """Send ``Value:r,g,b`` (again every :attr:`resend_s`) until ``SHOT`` is read.

        Raises
        ------
        PatchDisplayError
            If no ``SHOT`` came within :attr:`timeout_s`, the engine closed
            the connection, or writing failed; the message names the address.
        """
        message = value_shot_message(rgb_dac)
        if self._closed:
            raise PatchDisplayError(f"the patch display {self.where} has been closed")
        self._drop_pending()
        deadline = time.monotonic() + self.timeout_s
        received, sent = bytearray(), 0
        while True:
            self._send(message)
            sent += 1
            resend_at = min(time.monotonic() + self.resend_s, deadline)
            while time.monotonic() < resend_at:
                received += self._receive(resend_at - time.monotonic(), message)
                if VALUE_SHOT_ACK in received:
                    _LOG.debug("patch %s < SHOT", self.where)
                    return
                if len(received) > _MAX_PENDING_BYTES:
                    raise PatchDisplayError(
                        f"the engine at {self.where} sent {len(received)} bytes without {VALUE_SHOT_ACK.decode()} "
                        f"after {message.decode()}; is it the authors' Unreal project (value-shot convention)?")
            if time.monotonic() >= deadline:
                raise PatchDisplayError(
                    f"the engine at {self.where} did not answer {VALUE_SHOT_ACK.decode()} to {message.decode()} "
                    f"within {self.timeout_s:g} s (sent {sent} times, every "
                    f"{self.resend_s:g} s); check that the Unreal project is running and shows patches, "
                    "then run again with --resume")

    def _send(self, message: bytes) -> None:
        try:
            self._sock.sendall(message)
        except OSError as error:
            raise PatchDisplayError(
                f"the connection to the engine at {self.where} failed while sending {message.decode()} "
                f"({error}); restart the Unreal project and run again with --resume") from error
        self.sends += 1
        _LOG.debug("patch %s > %r", self.where, message)

    def _receive(self, wait_s: float, message: bytes) -> bytes:
        self._sock.settimeout(max(wait_s, 0.001))
        try:
            chunk = self._sock.recv(_RECEIVE_BYTES)
        except socket.timeout:
            return b""
        except OSError as error:
            raise PatchDisplayError(
                f"the connection to the engine at {self.where} failed while waiting for "
                f"{VALUE_SHOT_ACK.decode()} to {message.decode()} ({error}); restart the Unreal project "
                "and run again with --resume") from error
        if not chunk:
            raise PatchDisplayError(
                f"the engine at {self.where} closed the connection while the client waited for "
                f"{VALUE_SHOT_ACK.decode()} to {message.decode()}; restart the Unreal project and run "
                "again with --resume")
        return chunk

    def _drop_pending(self) -> None:
        """Read and drop what the engine sent since the last patch (late ``SHOT``s of re-sends)."""
        self._sock.setblocking(False)
        try:
            while True:
                chunk = self._sock.recv(_RECEIVE_BYTES)
                if not chunk:
                    break  # closed: the next send or receive says so
                _LOG.debug("patch %s: dropped %r received after the last SHOT", self.where, chunk)
        except (BlockingIOError, InterruptedError):
            pass
        except OSError:
            pass  # reported by the send that follows
        finally:
            self._sock.setblocking(True)

    def close(self) -> None:
        """Write ``DONE:0`` as the authors' script does at the end (best effort) and close."""
        if self._closed:
            return
        self._closed = True
        try:
            self._sock.sendall(VALUE_SHOT_DONE)
        except OSError as error:
            _LOG.info("engine %s: could not send %r (%s)", self.where, VALUE_SHOT_DONE, error)
        finally:
            self._sock.close()

    def describe(self) -> str:
        """The convention and the address, for the journal header."""
        return (f"engine via {self.where} (the authors' Unreal convention: Value:r,g,b until SHOT, "
                f"sent again every {self.resend_s:g} s)")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
