"""pyserial driver of the Konica Minolta CS-2000 / CS-2000A spectroradiometer.

The transport is injected (pymeasure style): :class:`CS2000` takes a device
name, which it opens with pyserial (115200 8N1, RTS/CTS only on a real USB
device), or any open serial-like object with ``read(n)``/``write(b)`` and
ideally ``in_waiting`` and a settable ``timeout`` (``serial.Serial``,
``serial.serial_for_url("loop://")``, a pty, a test double).

All I/O goes through one framing pair, :meth:`CS2000._write` and
:meth:`CS2000._read_line`, which log every frame at DEBUG on the
``instruments.cs2000`` logger and enforce a deadline on every wait.

Protocol facts follow the CS-2000 Communication Specifications
(KMSE-TI-08002) as summarised in design §6; see :mod:`.protocol`.
Units: seconds, nm, W·sr⁻¹·m⁻²·nm⁻¹, cd/m².
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Literal, NoReturn

import numpy as np
import serial
from serial.tools import list_ports

from instruments.cs2000.protocol import (
    ANGLE_DEGREES,
    WAVELENGTHS_NM,
    CS2000ConnectionError,
    CS2000Error,
    CS2000Timeout,
    MeasurementCancelled,
    MeasurementConditions,
    OverRangeError,
    PortVanishedError,
    ProtocolError,
    Reply,
    encode_command,
    error_from_reply,
    parse_colorimetry,
    parse_conditions,
    parse_reply,
    parse_spectral_block,
)

__all__ = [
    "USB_VID",
    "USB_PID",
    "PRE_MEASUREMENT_MAX_S",
    "Identity",
    "SpeedMode",
    "SyncMode",
    "INTERNAL_SYNC_RANGE_HZ",
    "Measurement",
    "PortSelectionError",
    "CS2000",
    "find_cs2000_ports",
    "open_cs2000",
]

logger = logging.getLogger("instruments.cs2000")

try:  # pyserial lets termios.error (not an OSError) escape from flush() on POSIX
    import termios

    _TERMIOS_ERRORS: tuple[type[BaseException], ...] = (termios.error,)
except ImportError:  # pragma: no cover - Windows
    _TERMIOS_ERRORS = ()
_PORT_ERRORS = (OSError, serial.SerialException, ValueError, *_TERMIOS_ERRORS)

USB_VID = 0x132B
"""USB vendor id of Konica Minolta."""
USB_PID = 0x2104
"""USB product id of the CS-2000 / CS-2000A (CDC serial)."""
PRE_MEASUREMENT_MAX_S = 10.0
"""Longest pre-measurement before ``OK00,ttt`` arrives (design §6: 1–10 s)."""

_ND_ON = 1
_SPEED_MODES = {0: "normal", 1: "fast", 2: "multi-integration normal", 3: "manual",
                4: "multi-integration fast"}  # fmt: skip
_SYNC_MODES = {0: "no sync", 1: "internal sync", 2: "external sync"}


class _CancelRequested(Exception):
    """Raised inside the read loop when the caller's cancel flag is set."""


@dataclass(frozen=True)
class Identity:
    """What ``IDDR`` reports.

    Attributes
    ----------
    name
        Product name as sent, padding removed (``"CS-2000"``).
    model
        ``"CS-2000"`` (variant code 1) or ``"CS-2000A"`` (variant code 2).
    serial
        The instrument's serial number, as a string.
    """

    name: str
    model: str
    serial: str


@dataclass(frozen=True)
class SpeedMode:
    """Speed mode (``SPMS``/``SPMR``).

    Attributes
    ----------
    mode
        0 normal, 1 fast, 2 multi-integration normal, 3 manual,
        4 multi-integration fast.
    integration_s
        Integration time in seconds for modes 2, 3 and 4 (whole seconds for
        2 and 4; µs resolution for 3); ``None`` for the automatic modes 0 and 1.
    nd
        Internal ND filter: 0 off, 1 on, 2 auto.
    """

    mode: int
    integration_s: float | None
    nd: int


INTERNAL_SYNC_RANGE_HZ = (20.0, 200.0)
"""Frequencies internal sync (``SCMS,1,f``) accepts, Hz; sent in 0.01 Hz steps (20.00–200.00)."""

_SYNC_NAMES = {0: "none", 1: "internal", 2: "external"}


@dataclass(frozen=True)
class SyncMode:
    """Synchronisation mode (``SCMS``/``SCMR``).

    Attributes
    ----------
    mode
        0 no sync, 1 internal (to ``frequency_hz``), 2 external.
    frequency_hz
        Internal sync frequency in Hz (20–200), ``None`` for modes 0 and 2.

    Examples
    --------
    >>> SyncMode.parse("internal:90")
    SyncMode(mode=1, frequency_hz=90.0)
    >>> SyncMode.parse("internal:89.91").text, SyncMode(0, None).text
    ('internal:89.91', 'none')
    """

    mode: int
    frequency_hz: float | None

    @classmethod
    def parse(cls, text: str) -> "SyncMode":
        """``none``, ``internal:HZ`` (20.00–200.00, 0.01 Hz steps) or ``external``.

        Raises
        ------
        ValueError
            Naming the bad text and what is accepted.
        """
        name, colon, rest = str(text).strip().partition(":")
        if name in ("none", "external") and not colon:
            return cls(0 if name == "none" else 2, None)
        low, high = INTERNAL_SYNC_RANGE_HZ
        if name == "internal" and colon:
            try:
                hz = float(rest)
            except ValueError:
                hz = math.nan
            if not math.isfinite(hz) or not low <= hz <= high:
                raise ValueError(f"sync {text!r}: internal sync takes {low:.2f}-{high:.2f} Hz (the panel's "
                                 "refresh rate, e.g. internal:90 for a 90 Hz HMD)")
            if abs(hz * 100 - round(hz * 100)) > 1e-6:
                raise ValueError(f"sync {text!r}: the CS-2000 sets internal sync in 0.01 Hz steps; give at "
                                 "most two decimals (e.g. internal:89.99)")
            return cls(1, round(hz * 100) / 100)
        raise ValueError(f"sync {text!r} is not understood; use none, internal:HZ ({low:g}-{high:g} Hz, "
                         "e.g. internal:90) or external")

    @property
    def text(self) -> str:
        """``none``, ``internal:HZ`` or ``external``, as :meth:`parse` reads it."""
        if self.mode == 1:
            return f"internal:{self.frequency_hz:g}"
        return _SYNC_NAMES[self.mode]


@dataclass(frozen=True, eq=False)
class Measurement:
    """One CS-2000 measurement.

    Attributes
    ----------
    wavelengths
        380..780 nm at 1 nm (401 values, read-only).
    radiance
        Spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹ (401 values, read-only); NaN
        where the instrument sent its "not computable" placeholder.
    XYZ
        CIE 1931 2° tristimulus values as computed by the instrument, cd/m²
        scale (``Y`` is the luminance); NaN where not computable.
    Lv
        Luminance in cd/m².
    xy
        CIE 1931 chromaticity; NaN where not computable (e.g. a black patch).
    colorimetry
        All 24 values of ``MEDR,2,0,00`` keyed by
        :data:`~instruments.cs2000.protocol.COLORIMETRIC_KEYS`; ``None`` where
        the instrument sent its "not computable" placeholder.
    integration_s
        Integration time the instrument used, in seconds.
    nd_used
        Whether the internal ND filter was in the light path.
    measurement_time_s
        The measurement time the instrument announced (``OK00,ttt``), seconds.
    conditions
        Everything ``MEDR,0,0,1`` reported.
    """

    wavelengths: np.ndarray
    radiance: np.ndarray
    XYZ: np.ndarray
    Lv: float
    xy: np.ndarray
    colorimetry: dict[str, float | None]
    integration_s: float
    nd_used: bool
    measurement_time_s: int
    conditions: MeasurementConditions


class PortSelectionError(CS2000ConnectionError):
    """No CS-2000, or more than one, was found; ``candidates`` lists the ports."""

    def __init__(self, meaning: str, advice: str, candidates: Sequence[tuple[str, str]]):
        super().__init__(meaning, advice)
        self.candidates = list(candidates)


class _NoModemLinesSerial(serial.Serial):
    """A pyserial port that never touches DTR/RTS.

    Setting modem lines on a pseudo-terminal raises ``OSError: [Errno 25]``
    (design §8); a CS-2000 over USB CDC does not need them either.
    """

    def _update_dtr_state(self) -> None:  # pragma: no cover - trivial
        pass

    def _update_rts_state(self) -> None:  # pragma: no cover - trivial
        pass


def _is_usb_device(device: str) -> bool:
    """Whether ``device`` is a USB serial port known to pyserial's list_ports."""
    real = os.path.realpath(device)
    for info in list_ports.comports():
        if info.vid is not None and os.path.realpath(info.device) == real:
            return True
    return False


def _open_serial(device: str, poll_interval_s: float, write_timeout_s: float) -> serial.Serial:
    usb = _is_usb_device(device)
    cls = serial.Serial if usb or os.name == "nt" else _NoModemLinesSerial
    port = cls()
    port.port = device
    port.baudrate = 115200
    port.bytesize = serial.EIGHTBITS
    port.parity = serial.PARITY_NONE
    port.stopbits = serial.STOPBITS_ONE
    port.rtscts = usb
    port.timeout = poll_interval_s
    port.write_timeout = write_timeout_s
    try:
        port.open()
    except _PORT_ERRORS as exc:
        raise CS2000ConnectionError(
            f"cannot open serial port {device} ({exc})",
            "Check the device name (find_cs2000_ports() lists CS-2000s), that the "
            "instrument is switched on and connected, that no other program holds the "
            "port, and that you may open it (Linux: be in the 'dialout' group).",
        ) from exc
    logger.debug("opened %s (115200 8N1, rtscts=%s)", device, usb)
    return port


def _cancel_predicate(cancel: Any) -> Callable[[], bool]:
    if cancel is None:
        return lambda: False
    if hasattr(cancel, "is_set"):
        return cancel.is_set
    if callable(cancel):
        return lambda: bool(cancel())
    raise TypeError("cancel must be a threading.Event, a callable returning bool, or None")


class CS2000:
    """Driver of one Konica Minolta CS-2000 / CS-2000A.

    Use it as a context manager: entering puts the instrument in remote mode
    (``RMTS,1``, or ``RMTS,2`` with ``no_flash_write``), leaving sends
    ``RMTS,0`` in a ``finally`` and closes a port the driver opened. A failing
    ``RMTS,0`` is logged as a warning, never raised: it must neither turn a
    finished block into an error nor mask the exception a block raised.

    Parameters
    ----------
    port
        A device name (``"/dev/ttyACM0"``, ``"COM3"``, ``"/dev/pts/4"``) that
        the driver opens with pyserial, or an open serial-like object.
    timeout_s
        Deadline for an ordinary reply, and the margin added to the
        instrument's announced times while measuring (pre-measurement up to
        10 s; the second ``MEAS`` line is awaited for ``ttt + timeout_s``).
        The specification asks for at least 10 s.
    no_flash_write
        ``True``: enter remote mode with ``RMTS,2`` (settings are not written
        to flash, which spares the flash memory in long automated sessions);
        ``"if-supported"``: try ``RMTS,2`` and fall back to ``RMTS,1`` if the
        instrument answers an error code (:attr:`remote_mode` tells which);
        ``False``: ``RMTS,1``.
    spectral_format
        ``"ascii"`` reads spectra with ``MEDR,1,0,b`` (5 significant digits),
        ``"float32"`` with ``MEDR,1,1,b`` (big-endian IEEE-754 hex).
    poll_interval_s
        Longest single blocking read; the cancel flag and progress are
        checked this often.
    clock
        Monotonic clock in seconds (a test seam).

    Examples
    --------
    >>> with CS2000("/dev/ttyACM0") as cs:          # doctest: +SKIP
    ...     print(cs.identify())
    ...     m = cs.measure(progress=lambda left, total: print(f"{left:.0f} s"))
    ...     print(m.Lv, m.xy)
    """

    def __init__(
        self,
        port: Any,
        timeout_s: float = 10.0,
        *,
        no_flash_write: bool | Literal["if-supported"] = False,
        spectral_format: Literal["ascii", "float32"] = "ascii",
        poll_interval_s: float = 0.05,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if not timeout_s > 0:
            raise ValueError(f"timeout_s must be positive, got {timeout_s!r}")
        if spectral_format not in ("ascii", "float32"):
            raise ValueError(
                f"spectral_format must be 'ascii' or 'float32', got {spectral_format!r}"
            )
        if not poll_interval_s > 0:
            raise ValueError(f"poll_interval_s must be positive, got {poll_interval_s!r}")
        self._timeout_s = float(timeout_s)
        if no_flash_write not in (False, True, "if-supported"):
            raise ValueError(
                f"no_flash_write must be False, True or 'if-supported', got {no_flash_write!r}"
            )
        self._no_flash_write = (
            no_flash_write if no_flash_write == "if-supported" else bool(no_flash_write)
        )
        self._spectral_format = spectral_format
        self._clock = clock
        self._rx = bytearray()
        self._in_remote = False
        self._remote_mode = 0
        self._port_lost = False
        if isinstance(port, (str, os.PathLike)):
            self._port_name = os.fspath(port)
            self._port = _open_serial(self._port_name, poll_interval_s, self._timeout_s)
            self._owns_port = True
        else:
            if not (hasattr(port, "read") and hasattr(port, "write")):
                raise TypeError("port must be a device name or an object with read(n) and write(b)")
            self._port = port
            self._owns_port = False
            name = getattr(port, "port", None) or getattr(port, "name", None)
            self._port_name = str(name or port)
            if hasattr(port, "timeout"):
                try:
                    port.timeout = poll_interval_s
                except (AttributeError, ValueError, OSError) as exc:
                    logger.debug("could not set the read timeout of %s: %s", self._port_name, exc)

    # ------------------------------------------------------------------ lifecycle

    @property
    def port_name(self) -> str:
        """Name of the serial port (device path or the object's description)."""
        return self._port_name

    @property
    def timeout_s(self) -> float:
        """Reply deadline in seconds."""
        return self._timeout_s

    def __enter__(self) -> CS2000:
        try:
            self.enter_remote()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, exc_type: Any, exc: BaseException | None, tb: Any) -> None:
        # Leaving remote mode is housekeeping: if RMTS,0 fails, the work of the
        # block is done (or its own exception is on its way out, and must not be
        # masked), so the failure is only logged, with what to do should the
        # instrument's keys stay locked.
        try:
            if self._in_remote and not self._port_lost:
                self.leave_remote()
            elif self._port_lost:
                logger.info("%s: port gone, not sending RMTS,0", self._port_name)
        except CS2000Error as err:
            logger.warning(
                "%s: could not leave remote mode (RMTS,0): %s; if the instrument's keys stay "
                "locked, switch it off and on", self._port_name, err
            )
        finally:
            self.close()

    @property
    def remote_mode(self) -> int:
        """0 local, 1 remote (``RMTS,1``), 2 remote without flash writes (``RMTS,2``)."""
        return self._remote_mode

    def enter_remote(self) -> None:
        """Enter remote mode: ``RMTS,1``, or ``RMTS,2`` as ``no_flash_write`` asks.

        With ``no_flash_write="if-supported"``, ``RMTS,2`` is tried first and an
        ``ERnn`` answer to it (firmware that does not know the mode) falls back
        to ``RMTS,1``; a timeout or a vanished port is raised as usual.
        """
        self._discard_stale_input(warn=False)
        mode = 1 if self._no_flash_write is False else 2
        try:
            self._query("RMTS", mode)
        except CS2000Error as err:
            if self._no_flash_write != "if-supported" or err.code is None:
                raise
            logger.info("%s: RMTS,2 answered %s; entering remote mode with RMTS,1 (settings "
                        "may be written to flash)", self._port_name, err.code)
            mode = 1
            self._query("RMTS", mode)
        self._in_remote = True
        self._remote_mode = mode

    def leave_remote(self) -> None:
        """Leave remote mode (``RMTS,0``); the instrument's keys work again."""
        self._in_remote = False
        self._remote_mode = 0
        self._query("RMTS", 0)

    def close(self) -> None:
        """Close the port if this driver opened it (a passed-in object stays open)."""
        if self._owns_port:
            try:
                self._port.close()
            except _PORT_ERRORS as exc:
                logger.debug("closing %s: %s", self._port_name, exc)

    # ------------------------------------------------------------------ framing

    def _write(self, command: bytes) -> None:
        """Send one command frame (logged at DEBUG)."""
        self._discard_stale_input(warn=True)
        logger.debug("%s -> %r", self._port_name, command)
        try:
            self._port.write(command)
            flush = getattr(self._port, "flush", None)
            if flush is not None:
                flush()
        except serial.SerialTimeoutException as exc:
            raise CS2000Timeout(f"writing {command.strip().decode()}", self._timeout_s) from exc
        except _PORT_ERRORS as exc:
            raise self._lost(f"sending {command.strip().decode()}", exc) from exc

    def _read_line(
        self,
        deadline: float,
        waiting_for: str = "a reply",
        on_wait: Callable[[], bool] | None = None,
    ) -> bytes:
        """Return the next non-empty line (terminator removed), logged at DEBUG.

        CR, LF and CR LF all end a line. ``on_wait`` is called before every
        blocking read; returning ``True`` aborts the wait (cancellation).

        Raises
        ------
        CS2000Timeout
            If no complete line arrived before ``deadline`` (``clock`` time).
        PortVanishedError
            If the port fails (unplugged, closed) while reading.
        """
        started = self._clock()
        while True:
            line = self._pop_line()
            if line is not None:
                if line.strip(b" \t\x00"):
                    logger.debug("%s <- %r", self._port_name, line)
                    return line
                continue
            if self._clock() >= deadline:
                partial = bytes(self._rx)
                raise CS2000Timeout(waiting_for, deadline - started, partial)
            if on_wait is not None and on_wait():
                raise _CancelRequested
            self._rx += self._read_chunk(waiting_for)

    def _pop_line(self) -> bytes | None:
        rx = self._rx
        for i, byte in enumerate(rx):
            if byte in (0x0D, 0x0A):
                line = bytes(rx[:i])
                end = i + 1
                if byte == 0x0D and end < len(rx) and rx[end] == 0x0A:
                    end += 1
                del rx[:end]
                return line
        return None

    def _read_chunk(self, waiting_for: str) -> bytes:
        port = self._port
        try:
            waiting = getattr(port, "in_waiting", 0) or 0
            data = port.read(waiting if waiting > 0 else 1)
        except _PORT_ERRORS as exc:
            raise self._lost(f"waiting for {waiting_for}", exc) from exc
        return bytes(data or b"")

    def _discard_stale_input(self, warn: bool) -> None:
        """Drop bytes that arrived unasked before a new command is sent."""
        stale = bytes(self._rx)
        self._rx.clear()
        try:
            waiting = getattr(self._port, "in_waiting", 0) or 0
            if waiting > 0:
                stale += bytes(self._port.read(waiting) or b"")
        except _PORT_ERRORS as exc:
            raise self._lost("clearing the input buffer", exc) from exc
        if stale.strip(b"\r\n \t\x00"):
            log = logger.warning if warn else logger.debug
            log("%s: discarding %d unexpected bytes before the next command: %r",
                self._port_name, len(stale), stale)

    def _lost(self, during: str, exc: BaseException) -> PortVanishedError:
        """Remember that the port is gone; return the error to raise."""
        self._port_lost = True
        self._in_remote = False
        logger.warning("%s: port vanished during %s: %s", self._port_name, during, exc)
        return PortVanishedError(self._port_name, during, exc)

    def _read_reply(
        self,
        deadline: float,
        waiting_for: str,
        on_wait: Callable[[], bool] | None = None,
    ) -> Reply:
        """Return the next line that carries an ``OKnn``/``ERnn`` status.

        Lines without a status (line noise) are logged and skipped.
        """
        while True:
            line = self._read_line(deadline, waiting_for, on_wait)
            try:
                return parse_reply(line)
            except ProtocolError:
                logger.warning("%s: ignoring a line that is not a reply: %r", self._port_name, line)

    def _query(self, name: str, *params: object) -> Reply:
        """Send a command, wait for its reply, raise the typed error for ``ERnn``."""
        command = encode_command(name, *params)
        text = command.decode("ascii").strip()
        self._write(command)
        reply = self._read_reply(self._clock() + self._timeout_s, text)
        if not reply.ok:
            raise error_from_reply(reply, text)
        return reply

    # ------------------------------------------------------------------ settings

    def identify(self) -> Identity:
        """Read product name, variant and serial number (``IDDR``)."""
        reply = self._query("IDDR")
        if len(reply.fields) < 3:
            raise ProtocolError(f"IDDR reply has {len(reply.fields)} fields, expected 3", reply.raw)
        name, variant, serial_number = reply.fields[:3]
        models = {1: "CS-2000", 2: "CS-2000A"}
        try:
            model = models.get(int(variant), name)
        except ValueError:
            model = name
        return Identity(name=name, model=model, serial=serial_number)

    def speed_mode(self) -> SpeedMode:
        """Read the speed mode, integration time and internal ND setting (``SPMR``)."""
        reply = self._query("SPMR")
        f = reply.fields
        try:
            mode = int(f[0])
            if mode in (0, 1):
                return SpeedMode(mode, None, int(f[1]))
            if mode in (2, 4):
                return SpeedMode(mode, float(int(f[1])), int(f[2]))
            if mode == 3:
                return SpeedMode(mode, int(f[1]) / 1e6, int(f[2]))
        except (IndexError, ValueError) as exc:
            raise ProtocolError(f"SPMR reply: {exc}", reply.raw) from exc
        raise ProtocolError(f"SPMR reply has unknown speed mode {mode}", reply.raw)

    def set_speed_mode(
        self, mode: int, integration: float | None = None, nd: int | None = None
    ) -> None:
        """Set the speed mode (``SPMS``).

        Parameters
        ----------
        mode
            0 normal, 1 fast (automatic integration); 2 multi-integration
            normal, 4 multi-integration fast (``integration`` in whole seconds,
            1–16); 3 manual (``integration`` in seconds, 0.005–120, sent in µs).
        integration
            Integration time in seconds, required for modes 2, 3, 4.
        nd
            Internal ND filter: 0 off, 1 on, 2 auto; ``None`` keeps the
            current setting (read with ``SPMR``).
        """
        if mode not in _SPEED_MODES:
            raise ValueError(f"speed mode must be one of {_SPEED_MODES}, got {mode!r}")
        if nd is not None and nd not in (0, 1, 2):
            raise ValueError(f"nd must be 0 (off), 1 (on) or 2 (auto), got {nd!r}")
        if mode in (0, 1) and integration is not None:
            raise ValueError(f"speed mode {mode} ({_SPEED_MODES[mode]}) sets its own integration")
        if mode in (2, 4) and (
            integration is None or integration != int(integration) or not 1 <= integration <= 16
        ):
            raise ValueError(
                f"speed mode {mode} needs integration in whole seconds 1..16, got {integration!r}"
            )
        if mode == 3 and (integration is None or not 0.005 <= integration <= 120):
            raise ValueError(
                f"manual speed mode needs integration in seconds 0.005..120, got {integration!r}"
            )
        if nd is None:
            nd = self.speed_mode().nd
        self._send_speed_mode(SpeedMode(mode, integration, nd))

    def _send_speed_mode(self, setting: SpeedMode) -> None:
        mode, integration, nd = setting.mode, setting.integration_s, setting.nd
        if mode in (2, 4):
            self._query("SPMS", mode, f"{int(integration):02d}", nd)
        elif mode == 3:
            self._query("SPMS", mode, f"{round(integration * 1e6):09d}", nd)
        else:
            self._query("SPMS", mode, nd)

    def sync_mode(self) -> SyncMode:
        """Read the synchronisation mode (``SCMR``)."""
        reply = self._query("SCMR")
        try:
            mode = int(reply.fields[0])
            frequency = int(reply.fields[1]) / 100 if mode == 1 else None
        except (IndexError, ValueError) as exc:
            raise ProtocolError(f"SCMR reply: {exc}", reply.raw) from exc
        return SyncMode(mode, frequency)

    def set_sync_mode(self, mode: int, frequency_hz: float | None = None) -> None:
        """Set the synchronisation mode (``SCMS``).

        Parameters
        ----------
        mode
            0 no sync, 1 internal sync at ``frequency_hz``, 2 external sync.
        frequency_hz
            20–200 Hz for internal sync (e.g. the HMD refresh rate, 90 Hz);
            sent in 0.01 Hz units.
        """
        if mode not in _SYNC_MODES:
            raise ValueError(f"sync mode must be one of {_SYNC_MODES}, got {mode!r}")
        if mode == 1:
            low, high = INTERNAL_SYNC_RANGE_HZ
            if frequency_hz is None or not low <= frequency_hz <= high:
                raise ValueError(
                    f"internal sync needs frequency_hz in {low:g}..{high:g}, got {frequency_hz!r}"
                )
            self._query("SCMS", 1, round(frequency_hz * 100))
        else:
            if frequency_hz is not None:
                raise ValueError(f"sync mode {mode} ({_SYNC_MODES[mode]}) takes no frequency")
            self._query("SCMS", mode)

    @contextmanager
    def synchronised(self, sync: SyncMode) -> Iterator[SyncMode]:
        """Put the instrument in ``sync`` for a block (``SCMR``, ``SCMS``); the previous mode is put back.

        Yields the previous mode. Putting it back is best effort: a failure
        then is logged, not raised (the block's own outcome stands).

        Examples
        --------
        >>> with meter.synchronised(SyncMode.parse("internal:90")):  # doctest: +SKIP
        ...     measurement = meter.measure()  # sent SCMS,1,9000 before
        """
        previous = self.sync_mode()
        self.set_sync_mode(sync.mode, sync.frequency_hz)
        logger.info("%s: sync %s (was %s)", self._port_name, sync.text, previous.text)
        try:
            yield previous
        finally:
            if previous != sync:
                try:
                    self.set_sync_mode(previous.mode, previous.frequency_hz)
                except (CS2000Error, ValueError, *_PORT_ERRORS) as err:
                    logger.error("%s: could not put the sync back to %s: %s", self._port_name, previous.text, err)

    def measuring_angle(self) -> float:
        """Read the measuring angle in degrees (``STSR``: 1, 0.2 or 0.1).

        The angle is set by the knob on the instrument; there is no setter.
        """
        reply = self._query("STSR")
        try:
            return ANGLE_DEGREES[int(reply.fields[0])]
        except (IndexError, ValueError, KeyError) as exc:
            raise ProtocolError(f"STSR reply: unknown angle code ({exc})", reply.raw) from exc

    # ------------------------------------------------------------------ measuring

    def measure(
        self,
        progress: Callable[[float, float], None] | None = None,
        cancel: Any = None,
    ) -> Measurement:
        """Measure and read spectral radiance and colorimetric values.

        Sends ``MEAS,1``; after the pre-measurement the instrument answers
        ``OK00,ttt`` (seconds still to go), reported as
        ``progress(remaining_s, total_s)`` and then about once a second; the
        second, unsolicited line is awaited for ``ttt + timeout_s`` seconds
        and no other command is sent before it arrived or timed out. Then
        ``MEDR,1,f,1..4``, ``MEDR,2,0,00`` and ``MEDR,0,0,1`` are read.

        On ER10 (over range) the measurement is retried once with the
        internal ND filter on; the previous speed mode is restored afterwards
        either way.

        Parameters
        ----------
        progress
            Called with (remaining seconds, total seconds).
        cancel
            A :class:`threading.Event` or a callable returning ``True`` to
            cancel; checked every ``poll_interval_s``. Cancelling sends
            ``MEAS,0`` and raises :class:`MeasurementCancelled`.

        Raises
        ------
        OverRangeError
            Still over range with the internal ND filter on.
        CS2000Timeout
            A reply did not arrive in time (``MEAS,0`` is then sent, best effort).
        MeasurementCancelled
            ``cancel`` was set.
        PortVanishedError
            The port disappeared.
        CS2000Error
            Any other instrument error (ER83 angle knob, ER51/52 temperature, …).
        """
        should_cancel = _cancel_predicate(cancel)
        if should_cancel():
            raise MeasurementCancelled("the start (nothing was sent)")
        try:
            countdown = self._run_measurement(progress, should_cancel)
        except OverRangeError as first:
            return self._measure_with_nd(first, progress, should_cancel)
        return self._read_measurement(countdown)

    def _measure_with_nd(
        self,
        first: OverRangeError,
        progress: Callable[[float, float], None] | None,
        should_cancel: Callable[[], bool],
    ) -> Measurement:
        previous = self.speed_mode()
        if previous.nd == _ND_ON:
            raise first
        logger.warning("%s: over range (ER10); retrying once with the internal ND filter on",
                       self._port_name)
        self._send_speed_mode(SpeedMode(previous.mode, previous.integration_s, _ND_ON))
        try:
            try:
                countdown = self._run_measurement(progress, should_cancel)
            except OverRangeError as second:
                raise OverRangeError(
                    second.code,
                    second.raw_reply,
                    second.meaning + ", even with the internal ND filter on",
                    "The target is brighter than the instrument can measure with its internal "
                    "ND filter: use a smaller measuring angle (0.2° or 0.1°), an external ND "
                    "filter, or lower the display brightness. If the source flickers, "
                    "synchronise to its frequency (set_sync_mode).",
                ) from first
            measurement = self._read_measurement(countdown)
        except BaseException:
            self._restore_speed_mode(previous, raise_errors=False)
            raise
        self._restore_speed_mode(previous, raise_errors=True)
        return measurement

    def _restore_speed_mode(self, previous: SpeedMode, raise_errors: bool) -> None:
        try:
            self._send_speed_mode(previous)
            logger.info("%s: speed mode restored to %s", self._port_name, previous)
        except CS2000Error as err:
            if raise_errors:
                raise
            logger.error(
                "%s: could not restore the speed mode %s: %s", self._port_name, previous, err
            )

    def _run_measurement(
        self,
        progress: Callable[[float, float], None] | None,
        should_cancel: Callable[[], bool],
    ) -> int:
        """``MEAS,1`` up to and including the second line; return ``ttt``.

        Whatever interrupts the wait (cancel flag, timeout, a garbled
        countdown, ``KeyboardInterrupt``, an exception from ``progress``)
        stops the instrument with ``MEAS,0`` so that it is left idle.
        """
        self._write(encode_command("MEAS", 1))
        try:
            return self._await_measurement(progress, should_cancel)
        except _CancelRequested as request:
            self._cancel_measurement(str(request))
        except CS2000Timeout:
            self._stop_measurement("its end did not arrive in time")
            raise
        except ProtocolError:
            self._stop_measurement("its reply was not understood")
            raise
        except CS2000Error:  # an ERnn reply ended it, or the port is gone
            raise
        except BaseException:
            self._stop_measurement("the caller was interrupted")
            raise

    def _await_measurement(
        self,
        progress: Callable[[float, float], None] | None,
        should_cancel: Callable[[], bool],
    ) -> int:
        started = self._clock()
        try:
            first = self._read_reply(
                started + PRE_MEASUREMENT_MAX_S + self._timeout_s,
                "MEAS,1 (pre-measurement)",
                on_wait=should_cancel,
            )
        except _CancelRequested:
            raise _CancelRequested("the pre-measurement") from None
        if not first.ok:
            raise error_from_reply(first, "MEAS,1")
        try:
            countdown = int(first.fields[0]) if first.fields else 242
        except ValueError as exc:
            raise ProtocolError(
                f"MEAS,1 countdown {first.fields[0]!r} is not a number", first.raw
            ) from exc
        total = float(countdown)
        counting_from = self._clock()
        logger.info("%s: measuring, %d s to go", self._port_name, countdown)
        last_whole = [countdown + 1]

        def tick() -> bool:
            if should_cancel():
                return True
            if progress is not None:
                remaining = max(0.0, total - (self._clock() - counting_from))
                if int(remaining) < last_whole[0]:
                    last_whole[0] = int(remaining)
                    progress(remaining, total)
            return False

        try:
            if tick():
                raise _CancelRequested
            second = self._read_reply(
                counting_from + total + self._timeout_s,
                f"MEAS,1 (end of the {countdown} s measurement)",
                on_wait=tick,
            )
        except _CancelRequested:
            raise _CancelRequested("the measurement") from None
        if not second.ok:
            raise error_from_reply(second, "MEAS,1 (end of measurement)")
        if progress is not None:
            progress(0.0, total)
        return countdown

    def _cancel_measurement(self, during: str) -> NoReturn:
        """Stop the measurement with ``MEAS,0`` and raise MeasurementCancelled.

        No acknowledgement in time is logged (the cancel still stands); a
        vanished port raises :class:`PortVanishedError` instead.
        """
        logger.info("%s: cancelling %s (MEAS,0)", self._port_name, during)
        try:
            self._send_meas_0()
        except CS2000Timeout as exc:
            logger.warning("%s: no acknowledgement of MEAS,0: %s", self._port_name, exc)
        raise MeasurementCancelled(during)

    def _stop_measurement(self, why: str) -> None:
        """Best effort: stop a measurement that may still run (``MEAS,0``).

        Called while another exception propagates, which must not be masked:
        whatever goes wrong here is only logged.
        """
        logger.warning("%s: stopping the measurement (MEAS,0) because %s", self._port_name, why)
        try:
            self._send_meas_0()
        except CS2000Error as exc:
            logger.warning("%s: MEAS,0 got no clean acknowledgement: %s", self._port_name, exc)

    def _send_meas_0(self) -> None:
        """Send ``MEAS,0`` and read up to its acknowledgement.

        A late ``OK00,ttt`` of the stopped ``MEAS,1`` (the pre-measurement
        ended just before ``MEAS,0`` arrived) is skipped; an ``ERnn`` answer
        is logged, since the instrument is idle either way.

        Raises
        ------
        CS2000Timeout
            No acknowledgement within ``timeout_s``.
        PortVanishedError
            The port disappeared.
        """
        self._write(encode_command("MEAS", 0))
        deadline = self._clock() + self._timeout_s
        while True:
            reply = self._read_reply(deadline, "MEAS,0")
            if reply.fields:  # a late "OK00,ttt" of the stopped MEAS,1
                continue
            if not reply.ok:
                logger.warning("%s: MEAS,0 answered %s", self._port_name, reply.code)
            return

    def _read_measurement(self, countdown: int) -> Measurement:
        binary = self._spectral_format == "float32"
        blocks = []
        for block in (1, 2, 3, 4):
            reply = self._query("MEDR", 1, 1 if binary else 0, block)
            blocks.append(parse_spectral_block(reply, block, binary))
        radiance = np.concatenate(blocks)
        colorimetry = parse_colorimetry(self._query("MEDR", 2, 0, "00"))
        conditions = parse_conditions(self._query("MEDR", 0, 0, 1))

        def value(key: str) -> float:
            v = colorimetry[key]
            return float("nan") if v is None else float(v)

        XYZ = np.array([value("X"), value("Y"), value("Z")])
        xy = np.array([value("x"), value("y")])
        for array in (radiance, XYZ, xy):
            array.setflags(write=False)
        return Measurement(
            wavelengths=WAVELENGTHS_NM,
            radiance=radiance,
            XYZ=XYZ,
            Lv=value("Lv"),
            xy=xy,
            colorimetry=colorimetry,
            integration_s=conditions.integration_s,
            nd_used=conditions.nd_used,
            measurement_time_s=countdown,
            conditions=conditions,
        )


# ---------------------------------------------------------------------- discovery


def find_cs2000_ports() -> list[tuple[str, str]]:
    """List serial ports whose USB VID/PID is 0x132B/0x2104 (a CS-2000).

    Returns
    -------
    list of (device, description)
        Sorted by device name, for the user to choose from.
    """
    found = [
        (info.device, info.description or info.product or "CS-2000")
        for info in list_ports.comports()
        if info.vid == USB_VID and info.pid == USB_PID
    ]
    return sorted(found)


def open_cs2000(port: Any = None, **kwargs: Any) -> CS2000:
    """Open a CS-2000 on ``port``, or the only one connected when ``port`` is None.

    Parameters
    ----------
    port
        Device name or open serial object; ``None`` auto-detects by USB VID/PID.
    **kwargs
        Passed to :class:`CS2000`.

    Raises
    ------
    PortSelectionError
        No CS-2000, or several, found; the message lists the candidates.
    """
    if port is not None:
        return CS2000(port, **kwargs)
    found = find_cs2000_ports()
    if len(found) == 1:
        logger.info("auto-detected CS-2000 on %s (%s)", *found[0])
        return CS2000(found[0][0], **kwargs)
    if found:
        listing = "; ".join(f"{dev} ({desc})" for dev, desc in found)
        raise PortSelectionError(
            f"{len(found)} CS-2000s are connected: {listing}",
            "Choose one and pass its device name as the port.",
            found,
        )
    others = sorted((info.device, info.description or "") for info in list_ports.comports())
    listing = "; ".join(f"{dev} ({desc})" for dev, desc in others) or "none"
    raise PortSelectionError(
        f"no CS-2000 (USB {USB_VID:04X}:{USB_PID:04X}) found; serial ports present: {listing}",
        "Connect the instrument by USB and switch it on (Windows needs the Konica Minolta "
        "USB driver), or pass the port name explicitly.",
        others,
    )
