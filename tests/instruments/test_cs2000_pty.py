"""The real CS-2000 driver against the emulator over a real pseudo-terminal."""

from __future__ import annotations

import sys
import threading
import time

import colour
import numpy as np
import pytest

from instruments.cs2000 import (
    CS2000,
    CS2000Emulator,
    CS2000Error,
    CS2000Timeout,
    ErrorCode,
    ErrorFault,
    GarbageFault,
    MeasurementCancelled,
    OverRangeError,
    PortVanishedError,
    SpeedMode,
    SyncMode,
    TimeoutFault,
    VanishFault,
    serve_on_pty,
)
from instruments.cs2000.protocol import _CLASS_BY_CODE

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="needs POSIX pseudo-terminals")

SHAPE = colour.SpectralShape(380, 780, 1)
CMFS_2 = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE).values
D65 = colour.SDS_ILLUMINANTS["D65"].copy().align(SHAPE).values


def radiance_for(luminance_cd_m2: float) -> np.ndarray:
    return D65 * luminance_cd_m2 / (683.0 * D65 @ CMFS_2[:, 1])


def served(luminance=80.0, time_scale=0.0, faults=(), **kwargs):
    emulator = CS2000Emulator(lambda: radiance_for(luminance), time_scale=time_scale, seed=3,
                              faults=faults, **kwargs)  # fmt: skip
    return emulator, serve_on_pty(emulator)


def test_identify_and_measure_over_a_pty():
    emulator, server = served(luminance=80.0)
    with server:
        assert server.port.startswith("/dev/")
        with CS2000(server.port, timeout_s=2.0) as cs:
            assert emulator.remote_mode == 1
            identity = cs.identify()
            assert (identity.name, identity.model, identity.serial) == ("CS-2000", "CS-2000", "10001234")
            assert cs.measuring_angle() == 1.0
            progress = []
            m = cs.measure(progress=lambda left, total: progress.append((left, total)))
        assert emulator.remote_mode == 0 and emulator.received[-1] == "RMTS,0"
    assert m.radiance.shape == (401,) and m.wavelengths[0] == 380 and m.wavelengths[-1] == 780
    np.testing.assert_allclose(m.radiance, radiance_for(80.0), rtol=0.02, atol=1e-7)
    np.testing.assert_allclose(m.XYZ, 683.0 * m.radiance @ CMFS_2, rtol=1e-3)  # consistent
    assert m.Lv == pytest.approx(80.0, rel=0.005) and m.XYZ[1] == pytest.approx(m.Lv, rel=1e-4)
    np.testing.assert_allclose(m.xy, [0.3127, 0.3290], atol=1e-3)
    assert m.colorimetry["T"] == pytest.approx(6504, abs=20)
    assert m.nd_used is False and m.integration_s > 0 and m.measurement_time_s == 2
    remaining = [left for left, total in progress]
    assert {total for _, total in progress} == {2.0}
    assert remaining == sorted(remaining, reverse=True) and remaining[-1] == 0.0


class WatchedEmulator(CS2000Emulator):
    """Notes how many commands had arrived each time a measurement ended, and any command fed mid-measurement."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.received_at_end: list[int] = []
        self.fed_while_measuring: list[bytes] = []

    def feed(self, data, now):
        if self.measuring:
            self.fed_while_measuring.append(bytes(data))
        return super().feed(data, now)

    def poll(self, now):
        was_measuring = self.measuring
        out = super().poll(now)
        if was_measuring and not self.measuring:
            self.received_at_end.append(len(self.received))
        return out


def test_no_command_reaches_the_emulator_between_meas_1_and_the_end_of_the_measurement():
    emulator = WatchedEmulator(lambda: radiance_for(0.1), time_scale=0.01, seed=3)
    with serve_on_pty(emulator) as server, CS2000(server.port, timeout_s=2.0) as cs:
        started = time.monotonic()
        m = cs.measure(progress=lambda left, total: None)
        took = time.monotonic() - started
        cs.identify()
    # when the measurement ended the emulator had received RMTS,1 and MEAS,1, nothing after MEAS,1
    assert emulator.received_at_end == [2] and emulator.received[1] == "MEAS,1"
    assert m.measurement_time_s == 39 and took >= (6.9 + 39) * 0.01  # it really waited (scaled)
    assert emulator.fed_while_measuring == []
    assert emulator.received[:3] == ["RMTS,1", "MEAS,1", "MEDR,1,0,1"]


def test_float32_spectra_and_settings_over_a_pty():
    emulator, server = served(luminance=3.0)
    with server, CS2000(server.port, timeout_s=2.0, spectral_format="float32", no_flash_write=True) as cs:
        assert emulator.remote_mode == 2
        cs.set_speed_mode(3, 0.25, 0)
        assert cs.speed_mode() == SpeedMode(3, 0.25, 0)
        cs.set_speed_mode(1)  # keeps ND off
        assert cs.speed_mode() == SpeedMode(1, None, 0)
        cs.set_sync_mode(1, 90.0)
        assert cs.sync_mode() == SyncMode(1, 90.0)
        m = cs.measure()
    assert m.Lv == pytest.approx(3.0, rel=0.01)
    assert m.conditions.speed_mode == 1 and m.conditions.sync_mode == 1


def test_over_range_is_retried_with_the_nd_filter_and_the_mode_restored():
    emulator, server = served(luminance=1_000.0)  # above the range without the ND filter
    with server, CS2000(server.port, timeout_s=2.0) as cs:
        cs.set_speed_mode(0, nd=0)
        m = cs.measure()
        assert m.nd_used is True and m.Lv == pytest.approx(1_000.0, rel=0.01)
        assert cs.speed_mode() == SpeedMode(0, None, 0)
    assert "SPMS,0,1" in emulator.received


def test_over_range_even_with_the_nd_filter():
    emulator, server = served(luminance=20_000.0)
    with server, CS2000(server.port, timeout_s=2.0) as cs:
        cs.set_speed_mode(0, nd=0)
        with pytest.raises(OverRangeError, match="even with the internal ND filter"):
            cs.measure()
        assert cs.speed_mode() == SpeedMode(0, None, 0)


@pytest.mark.parametrize("entry", list(ErrorCode), ids=lambda e: e.name)
def test_each_injected_error_code_reaches_the_caller_typed(entry):
    faults = [ErrorFault(entry.name, command="MEAS,1")]
    if entry.name == "ER10":  # the driver retries over-range once with the ND filter
        faults.append(ErrorFault("ER10", command="MEAS,1", nth=2))
    emulator, server = served(faults=faults)
    with server, CS2000(server.port, timeout_s=2.0) as cs:
        with pytest.raises(CS2000Error) as info:
            cs.measure()
        assert type(info.value) is _CLASS_BY_CODE[entry.name]
        assert info.value.code == entry.name
        if entry.name == "ER10":  # after the ND retry the advice goes beyond the ND filter
            assert "even with the internal ND filter on" in info.value.meaning
        else:
            assert info.value.advice == entry.advice
        cs.identify()  # the link is still usable


def test_error_at_the_end_of_the_measurement():
    emulator, server = served(faults=[ErrorFault("ER71", command="MEAS,1", line=2)])
    with server, CS2000(server.port, timeout_s=2.0) as cs:
        with pytest.raises(CS2000Error, match="ER71"):
            cs.measure()
        assert cs.measure().radiance.shape == (401,)


def test_missing_second_line_times_out():
    emulator, server = served(faults=[TimeoutFault()])
    with server, CS2000(server.port, timeout_s=0.3) as cs:
        started = time.monotonic()
        with pytest.raises(CS2000Timeout, match="end of the 2 s measurement"):
            cs.measure()
        assert time.monotonic() - started >= 2.3
        assert emulator.received[-1] == "MEAS,0"  # the driver stopped it
        assert cs.measure().radiance.shape == (401,)


def test_a_lost_command_times_out():
    emulator, server = served(faults=[TimeoutFault(command="IDDR", line=1)])
    with server, CS2000(server.port, timeout_s=0.3) as cs:
        with pytest.raises(CS2000Timeout, match="IDDR"):
            cs.identify()
        assert cs.identify().serial == "10001234"


@pytest.mark.parametrize("garbage", [b"\x00\xfe#~", b"\xffnoise\r\n", b"\n\n"])
def test_junk_before_replies(garbage):
    faults = [GarbageFault(garbage, command="IDDR"), GarbageFault(garbage, command="MEAS,1"),
              GarbageFault(garbage, command="MEDR,1,0,3")]  # fmt: skip
    emulator, server = served(faults=faults)
    with server, CS2000(server.port, timeout_s=2.0) as cs:
        assert cs.identify().serial == "10001234"
        assert cs.measure().radiance.shape == (401,)


def test_port_vanishing_mid_sequence():
    emulator, server = served(faults=[VanishFault(command="MEDR,1,0,3")])
    with server:
        cs = CS2000(server.port, timeout_s=2.0)
        with pytest.raises(PortVanishedError) as info:
            with cs:
                cs.measure()
        assert server.vanished
    message = str(info.value)
    assert server.port in message and "vanished" in message and "MEDR,1,0,3" in message
    assert "reconnect" in message.lower()


def test_port_vanishing_while_waiting_for_the_measurement():
    emulator, server = served(time_scale=1.0)
    with server, CS2000(server.port, timeout_s=2.0) as cs:
        timer = threading.Timer(0.2, server.vanish)
        timer.start()
        started = time.monotonic()
        with pytest.raises(PortVanishedError, match="MEAS,1"):
            cs.measure()
        assert time.monotonic() - started < 1.5
        timer.join()


def test_cancel_over_a_pty():
    emulator, server = served(time_scale=0.2)
    cancel = threading.Event()
    with server, CS2000(server.port, timeout_s=2.0) as cs:
        with pytest.raises(MeasurementCancelled):
            cs.measure(progress=lambda left, total: cancel.set(), cancel=cancel)
        assert emulator.received[-1] == "MEAS,0" and not emulator.measuring
        cancel.clear()
        emulator.time_scale = 0.0
        assert cs.measure(cancel=cancel).radiance.shape == (401,)


def test_opening_a_missing_port_is_a_clear_error():
    with pytest.raises(CS2000Error, match="cannot open serial port /dev/does-not-exist"):
        CS2000("/dev/does-not-exist")


def test_an_open_serial_object_is_used_as_given_and_left_open():
    import serial

    loop = serial.serial_for_url("loop://")
    cs = CS2000(loop, timeout_s=0.2)
    assert loop.timeout == pytest.approx(0.05)  # the driver polls with short reads
    with pytest.raises(CS2000Timeout, match="IDDR"):  # loop:// echoes; the echo is not a reply
        cs.identify()
    cs.close()
    assert loop.is_open
    loop.close()


def test_serve_on_pty_options_and_lifecycle():
    emulator = CS2000Emulator(lambda: radiance_for(10.0), time_scale=1.0)
    server = serve_on_pty(emulator, time_scale=0.0)
    assert emulator.time_scale == 0.0
    assert "serving" in repr(server) and not server.vanished
    server.vanish()
    assert server.vanished
    server.close()
    server.close()  # idempotent
    assert "closed" in repr(server) and server.error is None
