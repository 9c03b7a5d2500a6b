"""Konica Minolta CS-2000 spectroradiometer: driver, protocol, emulator, pty server.

* :mod:`.protocol`: framing, tolerant reply parsing, the error-code table and
  the typed exceptions;
* :mod:`.driver`: :class:`CS2000`, the pyserial driver (transport injected);
* :mod:`.emulator`: :class:`CS2000Emulator`, the protocol as a pure
  bytes-in/bytes-out state machine, with fault injection;
* :mod:`.pty_server`: :func:`serve_on_pty`, the emulator on a pseudo-terminal
  so that the real driver runs against it unchanged.
"""

from instruments.cs2000.driver import (
    CS2000,
    USB_PID,
    USB_VID,
    Identity,
    Measurement,
    PortSelectionError,
    SpeedMode,
    INTERNAL_SYNC_RANGE_HZ,
    SyncMode,
    find_cs2000_ports,
    open_cs2000,
)
from instruments.cs2000.emulator import (
    CS2000Emulator,
    ErrorFault,
    Fault,
    GarbageFault,
    MeasurementTiming,
    TimeoutFault,
    VanishFault,
    instrument_noise,
    measurement_timing,
    radiance_to_luminance,
)
from instruments.cs2000.protocol import (
    AngleKnobError,
    CommandError,
    CS2000ConnectionError,
    CS2000Error,
    CS2000Timeout,
    ErrorCode,
    FanError,
    InstrumentMemoryError,
    MeasurementCancelled,
    MeasurementConditions,
    MeasuringError,
    NDFilterError,
    NoCompensationError,
    NoDataError,
    OverRangeError,
    ParameterError,
    PortVanishedError,
    ProgramError,
    ProtocolError,
    ShutterError,
    SyncError,
    TemperatureError,
)
from instruments.cs2000.pty_server import PtyServer, serve_on_pty

__all__ = [
    # driver
    "CS2000",
    "Identity",
    "SpeedMode",
    "SyncMode",
    "INTERNAL_SYNC_RANGE_HZ",
    "Measurement",
    "MeasurementConditions",
    "find_cs2000_ports",
    "open_cs2000",
    "USB_VID",
    "USB_PID",
    # emulator
    "CS2000Emulator",
    "Fault",
    "ErrorFault",
    "TimeoutFault",
    "GarbageFault",
    "VanishFault",
    "instrument_noise",
    "MeasurementTiming",
    "measurement_timing",
    "radiance_to_luminance",
    "PtyServer",
    "serve_on_pty",
    # errors
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
    "PortSelectionError",
    "MeasurementCancelled",
]
