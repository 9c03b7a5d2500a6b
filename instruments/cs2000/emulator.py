"""CS-2000 emulator: a pure bytes-in/bytes-out state machine of the protocol.

:class:`CS2000Emulator` has no threads, no sleeps and no clock of its own:
:meth:`~CS2000Emulator.feed` takes the bytes the host sent and the current
time and returns what the instrument answers at once;
:meth:`~CS2000Emulator.poll` returns what has become due since (the
``OK00,ttt`` line after the pre-measurement, the unsolicited second line when
the measurement ends). The same core serves the byte-level tests and, through
:func:`instruments.cs2000.pty_server.serve_on_pty`, the real driver.

What it models (CS-2000 Communication Specifications, KMSE-TI-08002, as
summarised in design §6): remote mode (``RMTS``), ``IDDR``, speed mode
(``SPMS``/``SPMR``), sync mode (``SCMS``/``SCMR``), measuring angle (``STSR``),
``MEAS,1``/``MEAS,0`` with the two-line reply, ``MEDR,1,0|1,b``,
``MEDR,2,0,00`` (all 24 colorimetric values) and ``MEDR,0,0,1``; error codes
ER00 (unknown command, wrong parameter count, not in remote mode), ER02
(command while measuring), ER17 (bad parameter value, ``MEAS,1`` while
measuring), ER20 (no data), ER10 (over range), ER99 (the radiance source
failed). Other ``MEDR,2`` selectors than ``00`` answer ER17.

Timing model (:func:`measurement_timing`; seconds, multiplied by
``time_scale``): a pre-measurement of
1 s (bright) to 10 s (at the luminance floor), then the announced measurement
time ``ttt``: in normal mode about 1 s at ≥ 100 cd/m², growing as a power of
the luminance to the 242 s limit at the floor (0.003 cd/m² at 1°, 0.075 at
0.2°, 0.3 at 0.1°); fast mode grows to 16 s; multi-integration and manual
modes take twice the set integration time plus 1 s. ``ttt`` is reported as
the real instrument would (002–242) whatever the time scale.

Instrument noise (:func:`instrument_noise`): a whole-spectrum gain noise per
measurement (``repeatability``, 0.1 % by default), a multiplicative noise per
wavelength (``relative_noise``, 0.2 % by default) and
an absolute floor (``noise_floor``, W·sr⁻¹·m⁻²·nm⁻¹), drawn from a generator
seeded with ``seed``. Over range (ER10) above the angle's maximum luminance
(5 000 cd/m² at 1°) with the internal ND filter on or auto, ten times lower
with it off.

Colorimetric values are computed from the measured spectrum with
colour-science's CIE 1931 2° and CIE 1964 10° colour-matching functions,
``Lv = 683 × Σ L ȳ Δλ`` (Δλ = 1 nm); CCT and Δuv by Ohno (2013); dominant
wavelength and excitation purity against the equal-energy point.
"""

from __future__ import annotations

import functools
import logging
import math
import re
import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import colour
import numpy as np
from colour.temperature import uv_to_CCT_Ohno2013

__all__ = [
    "LUMINANCE_RANGE_CD_M2",
    "ND_TRANSMITTANCE",
    "NOT_COMPUTABLE",
    "ErrorFault",
    "TimeoutFault",
    "GarbageFault",
    "VanishFault",
    "Fault",
    "CS2000Emulator",
    "MeasurementTiming",
    "measurement_timing",
    "radiance_to_luminance",
    "instrument_noise",
]

logger = logging.getLogger("instruments.cs2000.emulator")

LUMINANCE_RANGE_CD_M2: dict[int, tuple[float, float]] = {
    0: (0.003, 5_000.0),
    1: (0.075, 125_000.0),
    2: (0.3, 500_000.0),
}
"""Angle code (0 = 1°, 1 = 0.2°, 2 = 0.1°) → (luminance floor, maximum) in cd/m²."""

ND_TRANSMITTANCE = 0.1
"""Modelled transmittance of the internal ND filter: without it the maximum
luminance is this fraction of :data:`LUMINANCE_RANGE_CD_M2`'s."""

NOT_COMPUTABLE = "-9.9999e9"
"""Placeholder the emulator sends for a value that cannot be computed."""

_K_M = 683.0
_BRIGHT_CD_M2 = 100.0
_FLOOR_1DEG = LUMINANCE_RANGE_CD_M2[0][0]
_MAX_S = {0: 242.0, 1: 16.0}
_N_WAVELENGTHS = 401
_BLOCK_SLICES = {1: slice(0, 100), 2: slice(100, 200), 3: slice(200, 300), 4: slice(300, 401)}
_CODE = re.compile(r"^ER\d\d$")


# ------------------------------------------------------------------------ faults


def _check_common(command: str | None, nth: int) -> None:
    if nth < 1:
        raise ValueError(f"nth counts matching commands from 1, got {nth}")
    if command is not None and not command.strip():
        raise ValueError("command must be a command prefix such as 'MEAS,1' or None")


@dataclass(frozen=True)
class ErrorFault:
    """The ``nth`` matching command answers ``code`` instead of its reply.

    Parameters
    ----------
    code
        ``"ERnn"``.
    command
        Prefix the command must start with (``"MEAS,1"``, ``"MEDR"``);
        ``None`` matches every command.
    nth
        Which matching command (1 = the next one), counted from when the
        fault was given to the emulator.
    line
        For ``MEAS,1``: 1 replaces the first reply (the measurement does not
        start), 2 lets it run and ends it with ``code`` instead of ``OK00``.
    """

    code: str
    command: str | None = None
    nth: int = 1
    line: int = 1

    def __post_init__(self) -> None:
        if not _CODE.match(self.code):
            raise ValueError(f"code must look like 'ER10', got {self.code!r}")
        if self.line not in (1, 2):
            raise ValueError(f"line must be 1 or 2, got {self.line}")
        _check_common(self.command, self.nth)


@dataclass(frozen=True)
class TimeoutFault:
    """A reply is never sent.

    With the default ``line=2`` the ``nth`` matching ``MEAS,1`` runs but
    never sends its second line (the data are still stored). With ``line=1``,
    or for a command other than ``MEAS,1``, the ``nth`` matching command is
    lost: no reply at all, no effect.
    """

    command: str | None = "MEAS,1"
    nth: int = 1
    line: int = 2

    def __post_init__(self) -> None:
        if self.line not in (1, 2):
            raise ValueError(f"line must be 1 or 2, got {self.line}")
        _check_common(self.command, self.nth)


@dataclass(frozen=True)
class GarbageFault:
    """Garbage bytes are sent before the reply to the ``nth`` matching command."""

    garbage: bytes = b"\x00\xfe#~"
    command: str | None = None
    nth: int = 1

    def __post_init__(self) -> None:
        if not self.garbage:
            raise ValueError("garbage must not be empty")
        _check_common(self.command, self.nth)


@dataclass(frozen=True)
class VanishFault:
    """The port vanishes when the ``nth`` matching command arrives (no reply).

    The emulator only flags it (:attr:`CS2000Emulator.vanished`); the pty
    server then closes its end so that the host sees the port disappear.
    """

    command: str | None = None
    nth: int = 1

    def __post_init__(self) -> None:
        _check_common(self.command, self.nth)


Fault = ErrorFault | TimeoutFault | GarbageFault | VanishFault


@dataclass
class _Armed:
    fault: Fault
    seen: int = 0

    def matches(self, command: str) -> bool:
        prefix = self.fault.command
        return prefix is None or command.upper().startswith(prefix.upper())


# ------------------------------------------------------------------------ formatting


def _fmt_e(value: float) -> str:
    """``1.2345e-3`` style: 5 significant digits, exponent without padding."""
    mantissa, exponent = f"{value:.4e}".split("e")
    return f"{mantissa}e{int(exponent):+d}"


def _fmt_sig5(value: float) -> str:
    """Five significant digits, fixed point where readable (``133.99``)."""
    magnitude = abs(value)
    if magnitude == 0:
        return "0.0000"
    if 1e-2 <= magnitude < 1e5:
        decimals = max(0, 4 - math.floor(math.log10(magnitude)))
        return f"{value:.{decimals}f}"
    return _fmt_e(value)


def _fmt_hex(value: float) -> str:
    return struct.pack(">f", value).hex().upper()


@dataclass(frozen=True)
class _Result:
    radiance: np.ndarray
    colorimetry: tuple[str, ...]
    conditions: tuple[str, ...]


@dataclass
class _Measurement:
    first_due: float
    first_line: str
    second_due: float
    second_line: str | None  # None: never sent (TimeoutFault)
    result: _Result | None
    terminator: bytes
    started_ok: bool = True


@functools.lru_cache(maxsize=2)
def _cmf_values(degrees: int) -> np.ndarray:
    """CIE 1931 2° (``degrees=2``) or 1964 10° colour-matching functions, 380..780 nm at 1 nm."""
    name = {2: "CIE 1931 2 Degree Standard Observer", 10: "CIE 1964 10 Degree Standard Observer"}
    cmfs = colour.colorimetry.MSDS_CMFS_STANDARD_OBSERVER[name[degrees]].copy()
    values = np.asarray(cmfs.align(colour.SpectralShape(380, 780, 1)).values, dtype=np.float64)
    values.setflags(write=False)
    return values


def radiance_to_luminance(radiance: np.ndarray) -> float:
    """Luminance in cd/m² of a spectral radiance, as the emulator computes it.

    ``Lv = 683 × Σ L(λ) ȳ(λ) Δλ`` over 380..780 nm at Δλ = 1 nm (CIE 1931 2°);
    ``radiance`` is 401 values in W·sr⁻¹·m⁻²·nm⁻¹.
    """
    return _K_M * float(np.asarray(radiance, dtype=np.float64) @ _cmf_values(2)[:, 1])


@dataclass(frozen=True)
class MeasurementTiming:
    """How long the emulated CS-2000 takes for one measurement, at real timing.

    Attributes
    ----------
    pre_measurement_s
        Seconds from ``MEAS,1`` to the ``OK00,ttt`` line (1 s bright … 10 s at
        the luminance floor).
    measurement_s
        ``ttt``: the whole seconds the instrument announces (2..242), from
        ``OK00,ttt`` to the second line.
    integration_s
        Integration time the instrument reports in its conditions, seconds.
    """

    pre_measurement_s: float
    measurement_s: int
    integration_s: float

    @property
    def duration_s(self) -> float:
        """Seconds from ``MEAS,1`` to the end of the measurement (data transfer excluded)."""
        return self.pre_measurement_s + self.measurement_s


def measurement_timing(
    luminance_cd_m2: float, mode: int = 0, integration_s: float | None = None, angle: int = 0
) -> MeasurementTiming:
    """The emulator's timing model: pre-measurement, ``ttt`` and integration time.

    Parameters
    ----------
    luminance_cd_m2
        Luminance of the target (:func:`radiance_to_luminance`).
    mode
        Speed mode: 0 normal, 1 fast (automatic integration), 2/4
        multi-integration, 3 manual.
    integration_s
        Set integration time in seconds for modes 2, 3 and 4.
    angle
        Measuring-angle code (0 = 1°, 1 = 0.2°, 2 = 0.1°): the luminance floor
        scales with it.

    Returns
    -------
    MeasurementTiming
        Unscaled (real) times; the emulator multiplies the waits by its
        ``time_scale`` but announces ``ttt`` as the real instrument would.

    Notes
    -----
    Modes 0 and 1: with ``darkness`` = 0 at ≥ 100 cd/m² and 1 at the angle's
    luminance floor (logarithmic in between), the measurement takes
    ``max_s ** darkness`` seconds (``max_s`` = 242 normal, 16 fast) and the
    pre-measurement ``1 + 9 × darkness``. Modes 2, 3, 4: a 1 s pre-measurement
    and twice the integration time plus 1 s. ``ttt`` is that time rounded up
    to whole seconds, within 2..242.

    Examples
    --------
    >>> measurement_timing(500.0)
    MeasurementTiming(pre_measurement_s=1.0, measurement_s=2, integration_s=0.5)
    """
    if mode in (0, 1):
        floor = LUMINANCE_RANGE_CD_M2[angle][0]
        equivalent = max(luminance_cd_m2, 1e-12) * (_FLOOR_1DEG / floor)
        span = math.log(_BRIGHT_CD_M2 / _FLOOR_1DEG)
        darkness = min(1.0, max(0.0, math.log(_BRIGHT_CD_M2 / equivalent) / span))
        total = math.exp(darkness * math.log(_MAX_S[mode]))
        pre, integration = 1.0 + 9.0 * darkness, total / 2
    elif mode in (2, 3, 4):
        if integration_s is None:
            raise ValueError(f"speed mode {mode} needs integration_s")
        pre, total, integration = 1.0, 2 * float(integration_s) + 1.0, float(integration_s)
    else:
        raise ValueError(f"speed mode must be 0..4, got {mode!r}")
    countdown = int(min(242, max(2, math.ceil(total - 1e-9))))
    return MeasurementTiming(pre, countdown, integration)


def instrument_noise(radiance: np.ndarray, rng: np.random.Generator, *, relative_noise: float = 0.002,
                     noise_floor: float = 2e-8, repeatability: float = 0.001, angle: int = 0) -> np.ndarray:
    """Radiance as the emulated CS-2000 measures it: the noise model of :class:`CS2000Emulator`.

    ``radiance`` is (401,) or (N, 401): per wavelength a multiplicative noise
    (``relative_noise``) and an additive floor (``noise_floor`` at 1°, scaled
    with the measuring angle's luminance range), and per measurement a
    whole-spectrum gain noise (``repeatability``).
    """
    radiance = np.asarray(radiance, dtype=float)
    floor = noise_floor * LUMINANCE_RANGE_CD_M2[angle][0] / _FLOOR_1DEG
    gain = 1.0 + relative_noise * rng.standard_normal(radiance.shape)
    common = 1.0 + repeatability * rng.standard_normal(radiance.shape[:-1] + (1,))
    return radiance * gain * common + floor * rng.standard_normal(radiance.shape)


class CS2000Emulator:
    """The CS-2000 serial protocol as a pure state machine.

    Parameters
    ----------
    radiance_source
        Called once per measurement (at ``MEAS,1``); returns the spectral
        radiance in front of the lens, 401 values at 380..780 nm, 1 nm,
        W·sr⁻¹·m⁻²·nm⁻¹.
    time_scale
        Multiplies every modelled duration: 1 = real timing, 0 = no waiting.
    seed
        Seed of the instrument-noise generator: an int, a
        :class:`numpy.random.SeedSequence` (e.g. ``SeedSequence([seed, n])``
        for the n-th continuation of a session), or ``None`` for fresh entropy.
    faults
        Faults to inject (:class:`ErrorFault`, :class:`TimeoutFault`,
        :class:`GarbageFault`, :class:`VanishFault`); more with :meth:`inject`.
    model
        1 for a CS-2000, 2 for a CS-2000A (``IDDR`` variant code).
    serial_number
        What ``IDDR`` reports.
    angle
        Measuring-angle knob position: 0 = 1°, 1 = 0.2°, 2 = 0.1°.
    relative_noise
        Standard deviation of the multiplicative noise per wavelength.
    noise_floor
        Standard deviation of the additive noise, W·sr⁻¹·m⁻²·nm⁻¹ (at 1°).
    repeatability
        Standard deviation of a whole-spectrum gain noise per measurement
        (the CS-2000 specifies 0.15 % 2σ luminance repeatability; default 0.1 %).

    Examples
    --------
    >>> import numpy as np
    >>> emu = CS2000Emulator(lambda: np.full(401, 1e-3), time_scale=0, seed=1)
    >>> emu.feed(b"RMTS,1\\r\\n", now=0.0)
    b'OK00\\r\\n'
    """

    def __init__(
        self,
        radiance_source: Callable[[], np.ndarray],
        time_scale: float = 1.0,
        seed: int | np.random.SeedSequence | None = None,
        faults: Sequence[Fault] = (),
        *,
        model: int = 1,
        serial_number: str = "10001234",
        angle: int = 0,
        relative_noise: float = 0.002,
        noise_floor: float = 2e-8,
        repeatability: float = 0.001,
    ) -> None:
        if model not in (1, 2):
            raise ValueError(f"model must be 1 (CS-2000) or 2 (CS-2000A), got {model!r}")
        if angle not in LUMINANCE_RANGE_CD_M2:
            raise ValueError(f"angle must be 0 (1°), 1 (0.2°) or 2 (0.1°), got {angle!r}")
        if relative_noise < 0 or noise_floor < 0 or repeatability < 0:
            raise ValueError("noise levels must not be negative")
        self._source = radiance_source
        self.time_scale = time_scale
        self._rng = np.random.default_rng(seed)
        self._model = model
        self._serial = serial_number
        self._angle = angle
        self._relative_noise = float(relative_noise)
        self._noise_floor = float(noise_floor)
        self._repeatability = float(repeatability)
        self._armed: list[_Armed] = []
        for fault in faults:
            self.inject(fault)
        self._rx = bytearray()
        self._skip_lf = False
        self._remote = 0
        self._speed: tuple[int, int | None, int] = (0, None, 2)  # mode, wire integration, nd
        self._sync: tuple[int, int | None] = (0, None)
        self._measurement: _Measurement | None = None
        self._last: _Result | None = None
        self._garbage = b""
        self._vanished = False
        self.received: list[str] = []
        """Every command received, in order (for tests and diagnostics)."""
        cmfs = colour.colorimetry.MSDS_CMFS_STANDARD_OBSERVER
        shape = colour.SpectralShape(380, 780, 1)
        self._cmfs = {
            2: cmfs["CIE 1931 2 Degree Standard Observer"].copy().align(shape),
            10: cmfs["CIE 1964 10 Degree Standard Observer"].copy().align(shape),
        }

    # ------------------------------------------------------------------ public state

    @property
    def time_scale(self) -> float:
        """Multiplier of every modelled duration (0 = instantaneous)."""
        return self._time_scale

    @time_scale.setter
    def time_scale(self, value: float) -> None:
        if not value >= 0:
            raise ValueError(f"time_scale must be >= 0, got {value!r}")
        self._time_scale = float(value)

    @property
    def vanished(self) -> bool:
        """Whether a :class:`VanishFault` fired: the port is gone."""
        return self._vanished

    @property
    def remote_mode(self) -> int:
        """0 local, 1 remote, 2 remote without flash writes."""
        return self._remote

    @property
    def measuring(self) -> bool:
        """Whether a measurement (pre-measurement included) is under way."""
        return self._measurement is not None

    def next_event_time(self) -> float | None:
        """When :meth:`poll` will next have something to send, or ``None``."""
        m = self._measurement
        if m is None:
            return None
        return m.first_due if m.first_line else m.second_due

    def inject(self, fault: Fault) -> None:
        """Arm a fault; its ``nth`` counts matching commands from now on."""
        if not isinstance(fault, ErrorFault | TimeoutFault | GarbageFault | VanishFault):
            raise TypeError(f"not a fault: {fault!r}")
        self._armed.append(_Armed(fault))

    # ------------------------------------------------------------------ byte interface

    def feed(self, data: bytes, now: float) -> bytes:
        """Take bytes from the host at time ``now`` (s); return the immediate reply bytes.

        Commands end with CR, LF or CR LF; each reply uses its command's
        terminator. Anything already due at ``now`` (with ``time_scale=0`` the
        whole two-line ``MEAS`` answer) is appended, in order.
        """
        if self._vanished:
            return b""
        self._rx += data
        out = bytearray()
        while not self._vanished:
            if self._skip_lf and self._rx[:1]:
                if self._rx[0] == 0x0A:
                    del self._rx[0]
                self._skip_lf = False
            command, terminator = self._next_command()
            if command is None:
                break
            if command.strip():
                out += self._handle(command, terminator, now)
            out += self.poll(now)
        if len(self._rx) > 4096:
            logger.warning("discarding %d bytes without a terminator", len(self._rx))
            self._rx.clear()
        out += self.poll(now)
        return bytes(out)

    def poll(self, now: float) -> bytes:
        """Return the lines that have become due by ``now`` (s)."""
        m = self._measurement
        if m is None or self._vanished:
            return b""
        out = bytearray()
        if m.first_line and now >= m.first_due:
            out += self._emit(m.first_line, m.terminator)
            m.first_line = ""
            if not m.started_ok:
                self._measurement = None
                return bytes(out)
        if not m.first_line and now >= m.second_due:
            self._measurement = None
            ended_ok = m.second_line in ("OK00", None)  # None: the line was lost, data kept
            self._last = m.result if ended_ok else None
            if m.second_line is None:
                logger.info("emulated fault: the end-of-measurement line is not sent")
            else:
                out += self._emit(m.second_line, m.terminator)
        return bytes(out)

    # ------------------------------------------------------------------ framing

    def _next_command(self) -> tuple[bytes | None, bytes]:
        rx = self._rx
        for i, byte in enumerate(rx):
            if byte == 0x0A:
                command = bytes(rx[:i])
                del rx[: i + 1]
                return command, b"\n"
            if byte == 0x0D:
                command = bytes(rx[:i])
                if i + 1 < len(rx):
                    crlf = rx[i + 1] == 0x0A
                    del rx[: i + (2 if crlf else 1)]
                    return command, b"\r\n" if crlf else b"\r"
                del rx[: i + 1]
                self._skip_lf = True  # a LF may still follow; the reply uses CR
                return command, b"\r"
        return None, b""

    def _emit(self, line: str, terminator: bytes) -> bytes:
        data = self._garbage + line.encode("ascii") + terminator
        self._garbage = b""
        return data

    # ------------------------------------------------------------------ commands

    def _fire_faults(self, command: str) -> list[Fault]:
        fired = []
        for armed in list(self._armed):
            if armed.matches(command):
                armed.seen += 1
                if armed.seen == armed.fault.nth:
                    fired.append(armed.fault)
                    self._armed.remove(armed)
        return fired

    def _handle(self, raw: bytes, terminator: bytes, now: float) -> bytes:
        text = raw.decode("ascii", errors="replace").strip()
        self.received.append(text)
        fired = self._fire_faults(text)
        for fault in fired:
            logger.info("emulated fault on %r: %s", text, fault)
        if any(isinstance(f, VanishFault) for f in fired):
            self._vanished = True
            return b""
        is_meas = text.upper().replace(" ", "").startswith("MEAS,1")
        if any(isinstance(f, TimeoutFault) and (f.line == 1 or not is_meas) for f in fired):
            return b""
        for fault in fired:
            if isinstance(fault, GarbageFault):
                self._garbage += fault.garbage
        errors = [f for f in fired if isinstance(f, ErrorFault)]
        error = next((f for f in errors if f.line == 1 or not is_meas), None)
        if error is not None:
            return self._emit(error.code, terminator)
        end_error = next((f.code for f in errors), None)
        drop_end = any(isinstance(f, TimeoutFault) for f in fired)
        line = self._dispatch(text, terminator, now, end_error, drop_end)
        return self._emit(line, terminator) if line is not None else b""

    def _dispatch(
        self, text: str, terminator: bytes, now: float, end_error: str | None, drop_end: bool
    ) -> str | None:
        """Return the reply line (without terminator), or None when it comes later."""
        name, *params = [p.strip() for p in text.split(",")]
        name = name.upper()
        if self._measurement is not None:
            if name == "MEAS" and params == ["0"]:
                logger.info("measurement cancelled by MEAS,0")
                self._measurement = None
                self._last = None
                return "OK00"
            if name == "MEAS" and params == ["1"]:
                return "ER17"
            return "ER02"
        if name == "RMTS":
            if len(params) != 1:
                return "ER00"
            if params[0] not in ("0", "1", "2"):
                return "ER17"
            self._remote = int(params[0])
            return "OK00"
        if not self._remote:
            return "ER00"
        handler = {
            "IDDR": self._iddr,
            "SPMS": self._spms,
            "SPMR": self._spmr,
            "SCMS": self._scms,
            "SCMR": self._scmr,
            "STSR": self._stsr,
            "MEDR": self._medr,
        }.get(name)
        if name == "MEAS":
            return self._meas(params, terminator, now, end_error, drop_end)
        if handler is None:
            return "ER00"
        return handler(params)

    def _iddr(self, params: list[str]) -> str:
        if params:
            return "ER00"
        product = "CS-2000" if self._model == 1 else "CS-2000A"
        return f"OK00,{product:<9},{self._model},{self._serial}"

    def _spms(self, params: list[str]) -> str:
        if not params or not params[0].isdigit():
            return "ER00" if not params else "ER17"
        mode = int(params[0])
        if mode not in (0, 1, 2, 3, 4):
            return "ER17"
        expected = 2 if mode in (0, 1) else 3
        if len(params) != expected:
            return "ER00"
        if not all(p.isdigit() for p in params[1:]):
            return "ER17"
        nd = int(params[-1])
        if nd not in (0, 1, 2):
            return "ER17"
        integration: int | None = None
        if mode in (2, 4):
            integration = int(params[1])
            if not 1 <= integration <= 16:
                return "ER17"
        elif mode == 3:
            integration = int(params[1])
            if not 5_000 <= integration <= 120_000_000:
                return "ER17"
        self._speed = (mode, integration, nd)
        return "OK00"

    def _spmr(self, params: list[str]) -> str:
        if params:
            return "ER00"
        mode, integration, nd = self._speed
        if mode in (2, 4):
            return f"OK00,{mode},{integration:02d},{nd}"
        if mode == 3:
            return f"OK00,{mode},{integration:09d},{nd}"
        return f"OK00,{mode},{nd}"

    def _scms(self, params: list[str]) -> str:
        if not params:
            return "ER00"
        if params[0] not in ("0", "1", "2"):
            return "ER17"
        mode = int(params[0])
        if len(params) != (2 if mode == 1 else 1):
            return "ER00"
        frequency = None
        if mode == 1:
            if not params[1].isdigit() or not 2_000 <= int(params[1]) <= 20_000:
                return "ER17"
            frequency = int(params[1])
        self._sync = (mode, frequency)
        return "OK00"

    def _scmr(self, params: list[str]) -> str:
        if params:
            return "ER00"
        mode, frequency = self._sync
        return f"OK00,{mode},{frequency}" if mode == 1 else f"OK00,{mode}"

    def _stsr(self, params: list[str]) -> str:
        return "ER00" if params else f"OK00,{self._angle}"

    def _medr(self, params: list[str]) -> str:
        if len(params) != 3:
            return "ER00"
        kind, form, selector = params
        if kind == "1":
            if form not in ("0", "1") or selector not in ("1", "2", "3", "4"):
                return "ER17"
            if self._last is None:
                return "ER20"
            values = self._last.radiance[_BLOCK_SLICES[int(selector)]]
            fmt = _fmt_hex if form == "1" else _fmt_e
            return "OK00," + ",".join(fmt(float(v)) for v in values)
        if kind == "2":
            if form != "0" or selector not in ("00", "0"):
                return "ER17"
            if self._last is None:
                return "ER20"
            return "OK00," + ",".join(self._last.colorimetry)
        if kind == "0":
            if form != "0" or selector != "1":
                return "ER17"
            if self._last is None:
                return "ER20"
            return "OK00," + ",".join(self._last.conditions)
        return "ER17"

    # ------------------------------------------------------------------ measuring

    def _meas(
        self,
        params: list[str],
        terminator: bytes,
        now: float,
        end_error: str | None,
        drop_end: bool,
    ) -> str | None:
        if len(params) != 1:
            return "ER00"
        if params[0] == "0":
            return "OK00"
        if params[0] != "1":
            return "ER17"
        self._last = None
        try:
            radiance = np.asarray(self._source(), dtype=np.float64)
            if radiance.shape != (_N_WAVELENGTHS,) or not np.all(np.isfinite(radiance)):
                raise ValueError(
                    f"radiance_source must return {_N_WAVELENGTHS} finite values (380..780 nm), "
                    f"got shape {radiance.shape}"
                )
        except Exception:
            logger.exception("the emulator's radiance source failed; answering ER99")
            return "ER99"
        luminance = radiance_to_luminance(radiance)
        mode, integration, nd = self._speed
        maximum = LUMINANCE_RANGE_CD_M2[self._angle][1]
        nd_used = nd == 1 or (nd == 2 and luminance > maximum * ND_TRANSMITTANCE)
        limit = maximum if nd_used else maximum * ND_TRANSMITTANCE
        if integration is None:
            set_integration_s = None
        else:  # the wire's whole seconds (modes 2, 4) or µs (mode 3)
            set_integration_s = float(integration) if mode in (2, 4) else integration / 1e6
        timing = measurement_timing(luminance, mode, set_integration_s, self._angle)
        first_due = now + timing.pre_measurement_s * self._time_scale
        if luminance > limit:
            logger.info("over range: %.4g cd/m² > %.4g cd/m² (ND %s)",
                        luminance, limit, "on" if nd_used else "off")
            self._measurement = _Measurement(
                first_due, "ER10", first_due, None, None, terminator, started_ok=False
            )
            return None
        countdown = timing.measurement_s
        measured = self._add_noise(radiance)
        conditions = (
            str(mode),
            str(self._sync[0]),
            f"{round(timing.integration_s * 1e6):09d}",
            "1" if nd_used else "0",
            "0",
            "0",
            str(self._angle),
            "00",
        )
        result = _Result(measured, self._colorimetry(measured), conditions)
        second_line = None if drop_end else (end_error or "OK00")
        self._measurement = _Measurement(
            first_due,
            f"OK00,{countdown:03d}",
            first_due + countdown * self._time_scale,
            second_line,
            result,
            terminator,
        )
        return None

    def _add_noise(self, radiance: np.ndarray) -> np.ndarray:
        return instrument_noise(radiance, self._rng, relative_noise=self._relative_noise,
                                noise_floor=self._noise_floor, repeatability=self._repeatability,
                                angle=self._angle)

    def _colorimetry(self, radiance: np.ndarray) -> tuple[str, ...]:
        values: list[str] = [_fmt_e(float(radiance.sum()))]
        for degrees in (2, 10):
            XYZ = _K_M * radiance @ _cmf_values(degrees)
            if degrees == 2:
                values.append(_fmt_sig5(float(XYZ[1])))
            values += [_fmt_e(float(v)) for v in XYZ]
            values += self._chromaticity(XYZ, degrees)
        return tuple(values)

    def _chromaticity(self, XYZ: np.ndarray, degrees: int) -> list[str]:
        X, Y, Z = (float(v) for v in XYZ)
        total = X + Y + Z
        if Y <= 0 or total <= 0 or X < 0 or Z < 0:
            return [NOT_COMPUTABLE] * 8
        x, y = X / total, Y / total
        denominator = X + 15 * Y + 3 * Z
        u_prime, v_prime = 4 * X / denominator, 9 * Y / denominator
        cct, duv = NOT_COMPUTABLE, NOT_COMPUTABLE
        try:
            uv_1960 = np.array([u_prime, v_prime * 2 / 3])
            t, d = (float(v) for v in uv_to_CCT_Ohno2013(uv_1960, cmfs=self._cmfs[degrees]))
            if 1_000 <= t <= 100_000 and abs(d) <= 0.05:
                cct, duv = f"{round(t):5d}", f"{d:+.4f}"
        except (ValueError, ArithmeticError) as exc:
            logger.debug("CCT not computable for xy=(%.4f, %.4f): %s", x, y, exc)
        wavelength, purity = NOT_COMPUTABLE, NOT_COMPUTABLE
        white = np.array([1 / 3, 1 / 3])
        xy = np.array([x, y])
        if np.hypot(*(xy - white)) > 1e-4:
            try:
                wl = float(colour.dominant_wavelength(xy, white, self._cmfs[degrees])[0])
                pe = float(colour.excitation_purity(xy, white, self._cmfs[degrees])) * 100
                if math.isfinite(wl) and math.isfinite(pe):
                    wavelength, purity = f"{wl:.2f}", f"{pe:.4f}"
            except (ValueError, ArithmeticError, IndexError) as exc:
                logger.debug("dominant wavelength not computable at xy=(%.4f, %.4f): %s", x, y, exc)
        chromaticity = [f"{v:.4f}" for v in (x, y, u_prime, v_prime)]
        return [*chromaticity, cct, duv, wavelength, purity]
