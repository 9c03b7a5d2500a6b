"""Framing, reply parsing and error codes of the Konica Minolta CS-2000.

What goes over the wire (Konica Minolta, *Spectroradiometer CS-2000
Communication Specifications*, technical note KMSE-TI-08002; design §6):

* a command is ASCII, its parameters separated by commas, ended by CR, LF or
  CR LF (:func:`encode_command` sends CR LF);
* a reply uses the same terminator and is ``OK00[,p1,...]`` or ``ERnn``;
* ``MEAS,1`` is answered twice: ``OK00,ttt`` after the pre-measurement (the
  seconds still to go), then an unsolicited ``OK00`` (or ``ERnn``) when the
  measurement ends.

Parsing is tolerant of what real links deliver: fields padded with zeros or
spaces (``002``, `` 5303``, ``+0.0065``), any of the three terminators, and
junk bytes before the status (a USB CDC port often delivers a stray byte after
being opened). Whatever is not a reply raises :class:`ProtocolError`.

Units: wavelengths in nm, spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹, radiance
``Le`` in W·sr⁻¹·m⁻², luminance and tristimulus values in cd/m², times in
seconds (the wire's µs are converted at the edge).
"""

from __future__ import annotations

import enum
import math
import re
import string
from dataclasses import dataclass

import numpy as np

__all__ = [
    "TERMINATOR",
    "WAVELENGTHS_NM",
    "SPECTRAL_BLOCKS",
    "COLORIMETRIC_KEYS",
    "NOT_COMPUTABLE_ABS",
    "ANGLE_DEGREES",
    "Reply",
    "MeasurementConditions",
    "ErrorCode",
    "CS2000Error",
    "CommandError",
    "MeasuringError",
    "NoCompensationError",
    "OverRangeError",
    "ParameterError",
    "NoDataError",
    "InstrumentMemoryError",
    "TemperatureError",
    "SyncError",
    "ShutterError",
    "NDFilterError",
    "AngleKnobError",
    "FanError",
    "ProgramError",
    "ProtocolError",
    "CS2000Timeout",
    "CS2000ConnectionError",
    "PortVanishedError",
    "MeasurementCancelled",
    "encode_command",
    "parse_reply",
    "error_from_reply",
    "parse_spectral_block",
    "parse_colorimetry",
    "parse_conditions",
]

TERMINATOR = b"\r\n"
"""Terminator this package sends; replies may end in CR, LF or CR LF."""

WAVELENGTHS_NM = np.arange(380, 781, dtype=np.float64)
"""The CS-2000's spectral sampling: 380..780 nm at 1 nm (401 values)."""
WAVELENGTHS_NM.setflags(write=False)

SPECTRAL_BLOCKS: dict[int, tuple[int, int]] = {
    1: (380, 100),
    2: (480, 100),
    3: (580, 100),
    4: (680, 101),
}
"""``MEDR,1,f,b`` block number → (first wavelength in nm, number of values)."""

COLORIMETRIC_KEYS: tuple[str, ...] = (
    "Le", "Lv", "X", "Y", "Z", "x", "y", "u_prime", "v_prime",
    "T", "delta_uv", "lambda_d", "Pe",
    "X10", "Y10", "Z10", "x10", "y10", "u_prime10", "v_prime10",
    "T10", "delta_uv10", "lambda_d10", "Pe10",
)  # fmt: skip
"""Order of the 24 values of ``MEDR,2,0,00``: radiance ``Le`` (W·sr⁻¹·m⁻²),
luminance ``Lv`` (cd/m²), then for the CIE 1931 2° observer X, Y, Z, x, y,
u′, v′, correlated colour temperature T (K), Δuv, dominant wavelength λd (nm,
negative for a complementary wavelength) and excitation purity Pe (%), then
the same eleven for the CIE 1964 10° observer."""

NOT_COMPUTABLE_ABS = 9.0e9
"""Values at or beyond this magnitude (the instrument sends ``-9.9999e9`` and
similar) are placeholders for "not computable": colorimetric values parse to
``None``, spectral radiance values to NaN."""

ANGLE_DEGREES: dict[int, float] = {0: 1.0, 1: 0.2, 2: 0.1}
"""``STSR`` and condition code → measuring angle in degrees."""

_STATUS = re.compile(rb"(OK|ER)(\d{2})")


def encode_command(name: str, *params: object) -> bytes:
    """Return the bytes of one command, parameters comma-separated, CR LF ended.

    Parameters
    ----------
    name
        Command name, e.g. ``"MEAS"``.
    *params
        Parameters, formatted with :func:`str` (format padding beforehand).

    Examples
    --------
    >>> encode_command("MEDR", 1, 0, 2)
    b'MEDR,1,0,2\\r\\n'
    """
    text = ",".join([name, *(str(p) for p in params)])
    if any(c in text for c in "\r\n") or not text.isascii():
        raise ValueError(f"command {text!r} must be one line of ASCII")
    return text.encode("ascii") + TERMINATOR


@dataclass(frozen=True)
class Reply:
    """One parsed reply line.

    Attributes
    ----------
    status
        ``"OK"`` or ``"ER"``.
    number
        The two-digit number after the status (``0`` for ``OK00``, ``10`` for ``ER10``).
    fields
        The parameters after the status, stripped of padding spaces.
    raw
        The line as received, without its terminator (junk included).
    """

    status: str
    number: int
    fields: tuple[str, ...]
    raw: bytes

    @property
    def ok(self) -> bool:
        """Whether the reply is ``OK00``."""
        return self.status == "OK"

    @property
    def code(self) -> str:
        """The four-character status, e.g. ``"OK00"`` or ``"ER83"``."""
        return f"{self.status}{self.number:02d}"


def parse_reply(raw: bytes) -> Reply:
    """Parse one reply line tolerantly.

    Junk bytes before the first ``OKnn``/``ERnn`` are skipped; fields are
    split on commas and stripped of surrounding spaces; trailing CR/LF and
    spaces are ignored.

    Raises
    ------
    ProtocolError
        If the line holds no ``OKnn``/``ERnn`` status.
    """
    match = _STATUS.search(raw)
    if match is None:
        raise ProtocolError(f"no OK/ER status in {raw!r}", raw_reply=raw)
    body = raw[match.end() :].rstrip(b"\r\n \t\x00")
    if body and not body.startswith(b","):
        raise ProtocolError(f"unexpected bytes after the status in {raw!r}", raw_reply=raw)
    text = body[1:].decode("ascii", errors="replace") if body else ""
    fields = tuple(f.strip() for f in text.split(",")) if body else ()
    return Reply(
        status=match.group(1).decode(),
        number=int(match.group(2)),
        fields=fields,
        raw=bytes(raw),
    )


# --------------------------------------------------------------------------- errors


class ErrorCode(enum.Enum):
    """Error check codes of the CS-2000 with their meaning and what to do.

    Meanings follow the error-check-code table of the CS-2000 Communication
    Specifications (KMSE-TI-08002); the advice is ours.
    """

    ER00 = (
        "ER00",
        "invalid command string or wrong number of parameters",
        "This is a driver or peer bug: check the command spelling and parameter count; "
        "if the instrument was just switched on, wait until its start-up screen has gone.",
    )
    ER02 = (
        "ER02",
        "the instrument is measuring; the command cannot be executed now",
        "Wait for the measurement to end (the second MEAS line) or cancel it with MEAS,0 "
        "before sending another command.",
    )
    ER05 = (
        "ER05",
        "no compensation values (user calibration, close-up lens or external ND factors "
        "selected but not set)",
        "Select factory calibration (channel 00) and no close-up lens / external ND on the "
        "instrument, or load the compensation values first.",
    )
    ER10 = (
        "ER10",
        "over measurement range, or too much flicker in the light source",
        "Use the internal ND filter (SPMS with ND on or auto), a smaller measuring angle, an "
        "external ND filter, or synchronise to the display refresh (SCMS) if it flickers.",
    )
    ER17 = (
        "ER17",
        "parameter error (value out of range), or MEAS sent while a measurement is running",
        "Check the parameter ranges of the command; do not start a measurement before the "
        "previous one has ended.",
    )
    ER20 = (
        "ER20",
        "no data: nothing has been measured (or stored) yet",
        "Run a measurement (MEAS,1) that ends with OK00 before reading data with MEDR.",
    )
    ER30 = (
        "ER30",
        "internal memory error",
        "Switch the instrument off and on; use RMTS,2 (no flash write) for long automated "
        "sessions; if it persists, contact Konica Minolta service.",
    )
    ER32 = (
        "ER32",
        "internal memory error",
        "Switch the instrument off and on; if it persists, contact Konica Minolta service.",
    )
    ER34 = (
        "ER34",
        "internal memory error",
        "Switch the instrument off and on; if it persists, contact Konica Minolta service.",
    )
    ER51 = (
        "ER51",
        "temperature abnormality (CCD cooling / Peltier)",
        "Let the instrument reach a stable temperature (ambient 5-35 °C, vents free, out "
        "of direct sun or lamp heat) for 10-15 minutes, then measure again.",
    )
    ER52 = (
        "ER52",
        "temperature abnormality (temperature sensor / count)",
        "Let the instrument reach a stable temperature (ambient 5-35 °C, vents free) for "
        "10-15 minutes, then measure again; if it persists, contact service.",
    )
    ER71 = (
        "ER71",
        "synchronisation signal out of range",
        "Check the sync frequency set with SCMS (20-200 Hz) or the external sync signal, "
        "or switch synchronisation off (SCMS,0).",
    )
    ER81 = (
        "ER81",
        "shutter malfunction",
        "Switch the instrument off and on; if it persists, the shutter needs service.",
    )
    ER82 = (
        "ER82",
        "internal ND filter malfunction",
        "Switch the instrument off and on; measure with the ND filter off (SPMS ...,0) "
        "until it is serviced.",
    )
    ER83 = (
        "ER83",
        "measuring-angle abnormality: the angle knob is between positions",
        "Turn the measuring-angle knob on the instrument fully to 1°, 0.2° or 0.1° until "
        "it clicks, then measure again.",
    )
    ER84 = (
        "ER84",
        "cooling fan malfunction",
        "Check that nothing blocks the fan; switch the instrument off and on; if it "
        "persists, contact service.",
    )
    ER99 = (
        "ER99",
        "program abnormality (instrument firmware error)",
        "Switch the instrument off and on; if it persists, contact Konica Minolta service.",
    )

    def __init__(self, code: str, meaning: str, advice: str) -> None:
        self.code = code
        self.meaning = meaning
        self.advice = advice


class CS2000Error(Exception):
    """Base class of every error this package raises about the CS-2000.

    Parameters
    ----------
    code
        The instrument's error check code (``"ER10"``), or ``None`` for errors
        that the link, not the instrument, reports (timeouts, a vanished port).
    raw_reply
        The reply line as received (``b""`` when there was none).
    meaning
        What the code means (the manual's wording, or a description of the fault).
    advice
        What the user should do about it.
    """

    def __init__(
        self,
        code: str | None,
        raw_reply: bytes = b"",
        meaning: str = "",
        advice: str = "",
    ) -> None:
        self.code = code
        self.raw_reply = bytes(raw_reply)
        self.meaning = meaning
        self.advice = advice
        head = f"CS-2000 {code}: {meaning}" if code else f"CS-2000: {meaning}"
        super().__init__(f"{head}. What to do: {advice}" if advice else head)


class CommandError(CS2000Error):
    """ER00: invalid command or parameter count."""


class MeasuringError(CS2000Error):
    """ER02: the instrument is measuring."""


class NoCompensationError(CS2000Error):
    """ER05: compensation values missing."""


class OverRangeError(CS2000Error):
    """ER10: over the measurement range (or too much flicker)."""


class ParameterError(CS2000Error):
    """ER17: parameter out of range, or MEAS while measuring."""


class NoDataError(CS2000Error):
    """ER20: no measurement data."""


class InstrumentMemoryError(CS2000Error):
    """ER30/ER32/ER34: internal memory error."""


class TemperatureError(CS2000Error):
    """ER51/ER52: temperature abnormality."""


class SyncError(CS2000Error):
    """ER71: synchronisation signal out of range."""


class ShutterError(CS2000Error):
    """ER81: shutter malfunction."""


class NDFilterError(CS2000Error):
    """ER82: internal ND filter malfunction."""


class AngleKnobError(CS2000Error):
    """ER83: the measuring-angle knob is between positions."""


class FanError(CS2000Error):
    """ER84: cooling fan malfunction."""


class ProgramError(CS2000Error):
    """ER99: firmware program abnormality."""


class ProtocolError(CS2000Error):
    """A reply that does not follow the protocol (no status, wrong field count)."""

    def __init__(self, problem: str, raw_reply: bytes = b"") -> None:
        super().__init__(
            None,
            raw_reply,
            f"unexpected reply: {problem}",
            "Check that the port really is a CS-2000 (not another device) and that no "
            "other program uses it; unplug and replug the USB cable if it persists.",
        )


class CS2000Timeout(CS2000Error, TimeoutError):
    """No (complete) reply arrived before the deadline."""

    def __init__(self, waiting_for: str, seconds: float, raw_reply: bytes = b"") -> None:
        super().__init__(
            None,
            raw_reply,
            f"no reply to {waiting_for} within {seconds:.1f} s",
            "Check that the instrument is switched on, in remote mode and connected; a "
            "measurement may take up to 242 s plus a 10 s pre-measurement at low "
            "luminance, so raise timeout_s if the target is very dark.",
        )
        self.waiting_for = waiting_for
        self.seconds = seconds


class CS2000ConnectionError(CS2000Error, ConnectionError):
    """The serial port cannot be opened or found."""

    def __init__(self, meaning: str, advice: str) -> None:
        super().__init__(None, b"", meaning, advice)


class PortVanishedError(CS2000ConnectionError):
    """The serial port disappeared while talking to the instrument."""

    def __init__(self, port: str, during: str, cause: BaseException | None = None) -> None:
        detail = f" ({cause})" if cause is not None else ""
        super().__init__(
            f"serial port {port} vanished during {during}{detail}",
            "The USB cable was pulled or the instrument was switched off: reconnect it, "
            "switch it on, and resume; the measurement in flight was lost.",
        )
        self.port = port
        self.during = during


class MeasurementCancelled(CS2000Error):
    """The caller cancelled a measurement; ``MEAS,0`` was sent."""

    def __init__(self, during: str = "the measurement") -> None:
        super().__init__(
            None,
            b"",
            f"measurement cancelled by the user during {during}",
            "Nothing to fix; start the measurement again when ready.",
        )


_CLASS_BY_CODE: dict[str, type[CS2000Error]] = {
    "ER00": CommandError,
    "ER02": MeasuringError,
    "ER05": NoCompensationError,
    "ER10": OverRangeError,
    "ER17": ParameterError,
    "ER20": NoDataError,
    "ER30": InstrumentMemoryError,
    "ER32": InstrumentMemoryError,
    "ER34": InstrumentMemoryError,
    "ER51": TemperatureError,
    "ER52": TemperatureError,
    "ER71": SyncError,
    "ER81": ShutterError,
    "ER82": NDFilterError,
    "ER83": AngleKnobError,
    "ER84": FanError,
    "ER99": ProgramError,
}


def error_from_reply(reply: Reply, context: str = "") -> CS2000Error:
    """Return the typed exception for an ``ERnn`` reply.

    Parameters
    ----------
    reply
        A parsed reply whose status is ``ER``.
    context
        What the driver was doing (``"MEAS,1"``), added to the meaning.
    """
    code = reply.code
    suffix = f" (in reply to {context})" if context else ""
    try:
        entry = ErrorCode[code]
    except KeyError:
        return CS2000Error(
            code,
            reply.raw,
            f"error code not in the CS-2000 specification{suffix}",
            "Note the code, switch the instrument off and on, and check its firmware version.",
        )
    return _CLASS_BY_CODE[code](code, reply.raw, entry.meaning + suffix, entry.advice)


# --------------------------------------------------------------------------- data


def _parse_float(token: str) -> float:
    return float(token.strip().replace(" ", ""))


def _excerpt(raw: bytes, limit: int = 60) -> str:
    """``raw`` for an error message: its repr, cut after ``limit`` bytes."""
    if len(raw) <= limit:
        return repr(raw)
    return f"{raw[:limit]!r}... ({len(raw)} bytes)"


def _parse_float32_hex(token: str, position: int, raw: bytes) -> bytes:
    """The 4 bytes of one big-endian float32 written as exactly 8 hex digits."""
    digits = token.replace(" ", "")
    if len(digits) != 8 or any(c not in string.hexdigits for c in digits):
        raise ProtocolError(
            f"spectral value {position + 1} is {token!r}, not a float32 in 8 hex digits, in the "
            f"reply {_excerpt(raw)}",
            raw,
        )
    return bytes.fromhex(digits)


def parse_spectral_block(reply: Reply, block: int, binary: bool) -> np.ndarray:
    """Parse the reply to ``MEDR,1,0,b`` (ASCII) or ``MEDR,1,1,b`` (float32 hex).

    Parameters
    ----------
    reply
        An ``OK00`` reply.
    block
        Block number 1..4 (380–479, 480–579, 580–679: 100 values; 680–780: 101).
    binary
        ``True`` for the big-endian IEEE-754 float32 hex form (exactly 8 hex
        digits per value), ``False`` for ASCII numbers such as ``1.2345e-3``.

    Returns
    -------
    numpy.ndarray
        Spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹, float64; NaN where the
        instrument sent its "not computable" placeholder (a magnitude of at
        least :data:`NOT_COMPUTABLE_ABS`, such as ``-9.9999e9``) or a
        non-finite value.

    Raises
    ------
    ProtocolError
        If the number of values is wrong or a value does not parse (a hex
        value with more or fewer than 8 digits included); the message quotes
        the reply.
    """
    start, count = SPECTRAL_BLOCKS[block]
    fields = reply.fields
    if len(fields) != count:
        raise ProtocolError(
            f"spectral block {block} ({start}-{start + count - 1} nm) has {len(fields)} "
            f"values, expected {count}",
            reply.raw,
        )
    if binary:
        data = b"".join(_parse_float32_hex(f, i, reply.raw) for i, f in enumerate(fields))
        values = np.frombuffer(data, dtype=">f4").astype(np.float64)
    else:
        try:
            values = np.array([_parse_float(f) for f in fields], dtype=np.float64)
        except ValueError as exc:
            raise ProtocolError(
                f"spectral block {block}: {exc}, in the reply {_excerpt(reply.raw)}", reply.raw
            ) from exc
    values[~(np.abs(values) < NOT_COMPUTABLE_ABS)] = np.nan  # placeholders, ±inf and NaN
    return values


def parse_colorimetry(reply: Reply) -> dict[str, float | None]:
    """Parse the 24 colorimetric values of ``MEDR,2,0,00``.

    Placeholders (``-9.9999e9`` and anything of that magnitude, or a field
    that is not a number, such as dashes) mean "not computable" and become
    ``None``.

    Returns
    -------
    dict
        :data:`COLORIMETRIC_KEYS` → value or ``None``.
    """
    if len(reply.fields) != len(COLORIMETRIC_KEYS):
        raise ProtocolError(
            f"colorimetric data has {len(reply.fields)} values, expected "
            f"{len(COLORIMETRIC_KEYS)}",
            reply.raw,
        )
    result: dict[str, float | None] = {}
    for key, token in zip(COLORIMETRIC_KEYS, reply.fields, strict=True):
        try:
            value = _parse_float(token)
        except ValueError:
            result[key] = None
            continue
        placeholder = not math.isfinite(value) or abs(value) >= NOT_COMPUTABLE_ABS
        result[key] = None if placeholder else value
    return result


@dataclass(frozen=True)
class MeasurementConditions:
    """Conditions of the last measurement (``MEDR,0,0,1``).

    Attributes
    ----------
    speed_mode
        0 normal, 1 fast, 2 multi-integration normal, 3 manual, 4 multi-integration fast.
    sync_mode
        0 none, 1 internal, 2 external.
    integration_s
        Integration time the instrument used, in seconds (µs on the wire).
    nd_used
        Whether the internal ND filter was in the light path.
    close_up_lens
        Close-up lens code (0 = none).
    external_nd
        External ND filter code (0 = none).
    angle_deg
        Measuring angle in degrees (1, 0.2 or 0.1).
    calibration_channel
        0 = factory calibration, 1..10 user calibrations.
    """

    speed_mode: int
    sync_mode: int
    integration_s: float
    nd_used: bool
    close_up_lens: int
    external_nd: int
    angle_deg: float
    calibration_channel: int


def parse_conditions(reply: Reply) -> MeasurementConditions:
    """Parse ``OK00,speed,sync,integration_µs,nd,lens,ext_nd,angle,channel``."""
    f = reply.fields
    if len(f) < 8:
        raise ProtocolError(f"measurement conditions have {len(f)} fields, expected 8", reply.raw)
    try:
        angle_code = int(f[6])
        return MeasurementConditions(
            speed_mode=int(f[0]),
            sync_mode=int(f[1]),
            integration_s=int(f[2]) / 1e6,
            nd_used=int(f[3]) == 1,
            close_up_lens=int(f[4]),
            external_nd=int(f[5]),
            angle_deg=ANGLE_DEGREES.get(angle_code, float("nan")),
            calibration_channel=int(f[7]),
        )
    except ValueError as exc:
        raise ProtocolError(f"measurement conditions: {exc}", reply.raw) from exc
