"""Byte-level tests of the CS-2000 driver, in the style of pymeasure's ``expected_protocol``.

A fake transport asserts the exact bytes the driver sends, feeds canned
replies, and checks at the end that every exchange was used. Time is a fake
clock advanced by the transport's read timeout, so deadlines are exercised
without waiting. Replies can be scripted at fake-clock times (the two lines of
``MEAS,1`` come seconds apart, as from the instrument), and the transport fails
the test if the driver writes anything while a scripted line is still due
(``MEAS,0``, which stops the measurement, excepted).
"""

from __future__ import annotations

import logging
import threading
from contextlib import contextmanager
from types import SimpleNamespace

import numpy as np
import pytest
import serial

from instruments.cs2000 import driver as driver_module
from instruments.cs2000 import (
    CS2000,
    AngleKnobError,
    CS2000Error,
    CS2000Timeout,
    ErrorCode,
    MeasurementCancelled,
    OverRangeError,
    PortSelectionError,
    PortVanishedError,
    ProtocolError,
    SpeedMode,
    SyncMode,
    TemperatureError,
    find_cs2000_ports,
    open_cs2000,
)
from instruments.cs2000.protocol import (
    COLORIMETRIC_KEYS,
    encode_command,
    error_from_reply,
    parse_colorimetry,
    parse_reply,
    parse_spectral_block,
)


class FakeClock:
    """A monotonic clock that only moves when told to."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


class FakeTransport:
    """Serial-like double: checks each command byte for byte, then delivers its reply.

    A reply is either bytes, available at once, or a list of ``(delay_s,
    line)`` that the instrument sends ``delay_s`` after the command, on the
    fake clock. A read with nothing available blocks as a real port would:
    for ``timeout`` seconds of fake time, or until the next scripted line
    falls due. Writing while a scripted line is still due fails the test, as
    design §6 forbids it, except ``MEAS,0``, which stops the measurement (its
    pending lines are then never sent).

    ``chunk`` limits how many bytes one read returns (1 = byte by byte).
    """

    def __init__(self, exchanges, clock: FakeClock, chunk: int | None = None) -> None:
        self.exchanges = list(exchanges)
        self.clock = clock
        self.chunk = chunk
        self.timeout = None
        self.sent = bytearray()
        self.rx = bytearray()
        self.pending: list[tuple[float, bytes]] = []  # (due time, line), in time order
        self.writes: list[bytes] = []
        self.write_times: list[tuple[float, bytes]] = []
        self.on_read = None

    def _release(self) -> None:
        while self.pending and self.pending[0][0] <= self.clock.now:
            self.rx += self.pending.pop(0)[1]

    @property
    def in_waiting(self) -> int:
        self._release()
        return min(len(self.rx), self.chunk) if self.chunk else len(self.rx)

    def write(self, data: bytes) -> int:
        self._release()
        if self.pending and not (bytes(self.sent) + data).startswith(b"MEAS,0"):
            due, line = self.pending[0]
            raise AssertionError(f"wrote {bytes(data)!r} at t={self.clock.now:.2f} s while the instrument's "
                                 f"line {line!r} was still due at t={due:.2f} s")
        self.sent += data
        assert self.exchanges, f"unexpected write {bytes(self.sent)!r}: no exchange left"
        expected, reply = self.exchanges[0]
        assert expected.startswith(bytes(self.sent)), f"sent {bytes(self.sent)!r}, expected {expected!r}"
        if bytes(self.sent) == expected:
            self.writes.append(expected)
            self.write_times.append((self.clock.now, expected))
            self.exchanges.pop(0)
            self.sent.clear()
            if expected.startswith(b"MEAS,0"):
                self.pending.clear()  # the measurement is stopped: its lines never come
            if isinstance(reply, bytes):
                self.rx += reply
            else:
                self.pending += [(self.clock.now + delay, line) for delay, line in reply]
                self.pending.sort(key=lambda item: item[0])
        return len(data)

    def read(self, n: int = 1) -> bytes:
        if self.on_read is not None:
            self.on_read()
        self._release()
        if not self.rx:
            timeout = self.timeout or 0.05
            if self.pending and self.pending[0][0] <= self.clock.now + timeout:
                self.clock.now = self.pending[0][0]  # a line arrives while the read blocks
                self._release()
            else:
                self.clock.now += timeout
                return b""
        n = min(n, self.chunk) if self.chunk else n
        data = bytes(self.rx[:n])
        del self.rx[:n]
        return data

    def assert_all_used(self) -> None:
        assert not self.exchanges, f"exchanges never used: {self.exchanges}"
        assert not self.sent, f"incomplete command sent: {bytes(self.sent)!r}"
        assert not self.rx.strip(b"\r\n"), f"replies never read: {bytes(self.rx)!r}"
        assert not self.pending, f"scripted lines never sent: {self.pending}"


@contextmanager
def expected_protocol(exchanges, chunk=None, **kwargs):
    """Yield a CS2000 on a fake transport that expects ``exchanges`` exactly."""
    clock = FakeClock()
    transport = FakeTransport(exchanges, clock, chunk)
    cs = CS2000(transport, clock=clock, **kwargs)
    cs.transport = transport  # for tests that inspect it
    yield cs
    transport.assert_all_used()


# ----------------------------------------------------------------------------- canned data

RADIANCE = np.linspace(1e-4, 5e-3, 401)


def spectral_reply(block: int, binary: bool = False, style: str = "instrument") -> bytes:
    start = {1: 0, 2: 100, 3: 200, 4: 300}[block]
    count = 101 if block == 4 else 100
    values = RADIANCE[start : start + count]
    if binary:
        fields = [np.array(v, dtype=">f4").tobytes().hex().upper() for v in values]
    elif style == "python":
        fields = [f"{v:.4e}" for v in values]  # two-digit exponent
    else:
        fields = [f"{v:.4e}".replace("e-0", "e-") for v in values]  # 1.2345e-3
    return ("OK00," + ",".join(fields) + "\r\n").encode()


COLORIMETRY = (
    "6.0544e-1,133.99,1.2620e+2,1.3399e+2,1.1334e+2,0.3379,0.3587,0.2039,0.4870, 5303,+0.0065,"
    "561.36,9.0400,1.3798e+2,1.4250e+2,1.2207e+2,0.3412,0.3569,0.2078,0.4885, 5140,+0.0060,"
    "563.10,-9.9999e9"
)
CONDITIONS = "0,0,000859000,1,0,0,0,00"


def readout(binary: bool = False, conditions: str = CONDITIONS):
    form = 1 if binary else 0
    return [
        *[(f"MEDR,1,{form},{b}\r\n".encode(), spectral_reply(b, binary)) for b in (1, 2, 3, 4)],
        (b"MEDR,2,0,00\r\n", f"OK00,{COLORIMETRY}\r\n".encode()),
        (b"MEDR,0,0,1\r\n", f"OK00,{conditions}\r\n".encode()),
    ]


IDDR_REPLY = b"OK00,CS-2000  ,1,10001234"


# ----------------------------------------------------------------------------- framing


def test_encode_command_uses_crlf_and_commas():
    assert encode_command("MEDR", 1, 0, 2) == b"MEDR,1,0,2\r\n"
    assert encode_command("IDDR") == b"IDDR\r\n"
    with pytest.raises(ValueError):
        encode_command("MEAS", "1\r\nRMTS,0")


@pytest.mark.parametrize(
    ("raw", "status", "fields"),
    [
        (b"OK00", "OK00", ()),
        (b"OK00,002", "OK00", ("002",)),
        (b"OK00,  2", "OK00", ("2",)),
        (b"OK00, 5303,+0.0065", "OK00", ("5303", "+0.0065")),
        (b"\x00\xfe#OK00,CS-2000  ,1,42", "OK00", ("CS-2000", "1", "42")),
        (b"ER83", "ER83", ()),
        (b"\xffER10 \r", "ER10", ()),
        (b"OK00,1\x00\x00", "OK00", ("1",)),
    ],
)
def test_parse_reply_is_tolerant(raw, status, fields):
    reply = parse_reply(raw)
    assert reply.code == status
    assert reply.fields == fields
    assert reply.raw == raw


def test_parse_reply_rejects_lines_without_status():
    with pytest.raises(ProtocolError):
        parse_reply(b"garbage")
    with pytest.raises(ProtocolError):
        parse_reply(b"OK00X")


@pytest.mark.parametrize("terminator", [b"\r", b"\n", b"\r\n"])
@pytest.mark.parametrize("chunk", [None, 1])
def test_identify_with_each_terminator_and_delivery(terminator, chunk):
    with expected_protocol([(b"IDDR\r\n", IDDR_REPLY + terminator)], chunk=chunk) as cs:
        identity = cs.identify()
    assert identity.name == "CS-2000"
    assert identity.model == "CS-2000"
    assert identity.serial == "10001234"


def test_identify_cs2000a():
    with expected_protocol([(b"IDDR\r\n", b"OK00,CS-2000A ,2,20005678\r\n")]) as cs:
        assert cs.identify().model == "CS-2000A"


def test_junk_bytes_before_the_reply_are_skipped():
    with expected_protocol([(b"IDDR\r\n", b"\xfe\x00#~" + IDDR_REPLY + b"\r\n")]) as cs:
        assert cs.identify().serial == "10001234"


def test_a_junk_line_before_the_reply_is_skipped_and_logged(caplog):
    with caplog.at_level(logging.WARNING, logger="instruments.cs2000"):
        with expected_protocol([(b"IDDR\r\n", b"~~noise~~\r\n" + IDDR_REPLY + b"\n")]) as cs:
            assert cs.identify().serial == "10001234"
    assert "not a reply" in caplog.text


def test_stale_input_is_discarded_before_a_command(caplog):
    with expected_protocol([(b"IDDR\r\n", IDDR_REPLY + b"\r\n")]) as cs:
        cs.transport.rx += b"OK00\r\n"  # left over from something nobody waited for
        with caplog.at_level(logging.WARNING, logger="instruments.cs2000"):
            assert cs.identify().serial == "10001234"
    assert "discarding" in caplog.text


def test_every_frame_is_logged_at_debug(caplog):
    with caplog.at_level(logging.DEBUG, logger="instruments.cs2000"):
        with expected_protocol([(b"IDDR\r\n", IDDR_REPLY + b"\r\n")]) as cs:
            cs.identify()
    assert "-> b'IDDR\\r\\n'" in caplog.text
    assert "<- b'OK00,CS-2000  ,1,10001234'" in caplog.text


# ----------------------------------------------------------------------------- remote mode


def test_context_manager_enters_and_leaves_remote_mode():
    with expected_protocol([(b"RMTS,1\r\n", b"OK00\r\n"), (b"IDDR\r\n", IDDR_REPLY + b"\r\n"),
                            (b"RMTS,0\r\n", b"OK00\r\n")]) as cs:  # fmt: skip
        with cs:
            cs.identify()


def test_no_flash_write_uses_rmts_2():
    with expected_protocol([(b"RMTS,2\r\n", b"OK00\r\n"), (b"RMTS,0\r\n", b"OK00\r\n")],
                           no_flash_write=True) as cs:  # fmt: skip
        with cs:
            pass


def test_remote_mode_is_left_even_when_the_body_fails():
    with expected_protocol([(b"RMTS,1\r\n", b"OK00\r\n"), (b"RMTS,0\r\n", b"OK00\r\n")]) as cs:
        with pytest.raises(RuntimeError, match="boom"):
            with cs:
                raise RuntimeError("boom")


def test_entering_remote_mode_error_is_typed():
    with expected_protocol([(b"RMTS,1\r\n", b"ER00\r\n")]) as cs:
        with pytest.raises(CS2000Error) as info:
            with cs:
                pass
    assert info.value.code == "ER00"


# ----------------------------------------------------------------------------- settings


@pytest.mark.parametrize(
    ("reply", "expected"),
    [
        (b"OK00,0,2\r\n", SpeedMode(0, None, 2)),
        (b"OK00,1,0\r\n", SpeedMode(1, None, 0)),
        (b"OK00,2,08,1\r\n", SpeedMode(2, 8.0, 1)),
        (b"OK00,4, 16,0\r\n", SpeedMode(4, 16.0, 0)),
        (b"OK00,3,000500000,1\r\n", SpeedMode(3, 0.5, 1)),
    ],
)
def test_speed_mode_read(reply, expected):
    with expected_protocol([(b"SPMR\r\n", reply)]) as cs:
        assert cs.speed_mode() == expected


@pytest.mark.parametrize(
    ("args", "sent"),
    [
        ((0, None, 0), b"SPMS,0,0\r\n"),
        ((1, None, 2), b"SPMS,1,2\r\n"),
        ((2, 8, 1), b"SPMS,2,08,1\r\n"),
        ((4, 16, 0), b"SPMS,4,16,0\r\n"),
        ((3, 0.5, 1), b"SPMS,3,000500000,1\r\n"),
        ((3, 0.005, 0), b"SPMS,3,000005000,0\r\n"),
    ],
)
def test_set_speed_mode_encodes_the_documented_forms(args, sent):
    with expected_protocol([(sent, b"OK00\r\n")]) as cs:
        cs.set_speed_mode(*args)


def test_set_speed_mode_keeps_the_current_nd_when_not_given():
    with expected_protocol([(b"SPMR\r\n", b"OK00,0,1\r\n"), (b"SPMS,1,1\r\n", b"OK00\r\n")]) as cs:
        cs.set_speed_mode(1)


@pytest.mark.parametrize(
    "args",
    [(5, None, 0), (0, 1.0, 0), (2, None, 0), (2, 2.5, 0), (2, 17, 0), (3, 0.001, 0),
     (3, 121, 0), (0, None, 3)],
)  # fmt: skip
def test_set_speed_mode_rejects_bad_values_without_sending(args):
    with expected_protocol([]) as cs:
        with pytest.raises(ValueError):
            cs.set_speed_mode(*args)


def test_sync_mode_read_and_set():
    exchanges = [
        (b"SCMR\r\n", b"OK00,1,6000\r\n"),
        (b"SCMS,1,9000\r\n", b"OK00\r\n"),
        (b"SCMS,0\r\n", b"OK00\r\n"),
        (b"SCMR\r\n", b"OK00,2\r\n"),
    ]
    with expected_protocol(exchanges) as cs:
        assert cs.sync_mode() == SyncMode(1, 60.0)
        cs.set_sync_mode(1, 90)
        cs.set_sync_mode(0)
        assert cs.sync_mode() == SyncMode(2, None)
        with pytest.raises(ValueError):
            cs.set_sync_mode(1, 10)
        with pytest.raises(ValueError):
            cs.set_sync_mode(0, 60)


@pytest.mark.parametrize(("code", "degrees"), [(b"0", 1.0), (b"1", 0.2), (b"2", 0.1)])
def test_measuring_angle(code, degrees):
    with expected_protocol([(b"STSR\r\n", b"OK00," + code + b"\r\n")]) as cs:
        assert cs.measuring_angle() == degrees


# ----------------------------------------------------------------------------- errors


@pytest.mark.parametrize("entry", list(ErrorCode), ids=lambda e: e.name)
def test_each_error_code_becomes_its_typed_exception(entry):
    with expected_protocol([(b"IDDR\r\n", f"{entry.name}\r\n".encode())]) as cs:
        with pytest.raises(CS2000Error) as info:
            cs.identify()
    error = info.value
    assert error.code == entry.name
    assert error.meaning.startswith(entry.meaning)
    assert error.advice == entry.advice and len(error.advice) > 20
    assert error.raw_reply == entry.name.encode()
    assert entry.name in str(error) and "What to do" in str(error)


@pytest.mark.parametrize(
    ("code", "cls"),
    [("ER10", OverRangeError), ("ER83", AngleKnobError), ("ER51", TemperatureError),
     ("ER52", TemperatureError)],
)  # fmt: skip
def test_required_exception_types(code, cls):
    error = error_from_reply(parse_reply(code.encode()), "MEAS,1")
    assert type(error) is cls
    assert "MEAS,1" in error.meaning


def test_angle_knob_advice_names_the_knob():
    assert "knob" in ErrorCode.ER83.advice
    assert "temperature" in ErrorCode.ER51.advice


def test_unknown_error_code_is_still_an_error():
    error = error_from_reply(parse_reply(b"ER45"))
    assert type(error) is CS2000Error and error.code == "ER45"


# ----------------------------------------------------------------------------- measuring


def measuring(countdown: int, pre_s: float = 1.0, end: bytes = b"OK00\r\n"):
    """The two ``MEAS,1`` lines as the instrument sends them: after the pre-measurement, then ``ttt`` later."""
    return [(pre_s, f"OK00,{countdown:03d}\r\n".encode()), (pre_s + countdown, end)]


def test_measure_reads_all_blocks_and_colorimetry():
    progress = []
    exchanges = [(b"MEAS,1\r\n", measuring(3, pre_s=1.5)), *readout()]
    with expected_protocol(exchanges) as cs:
        m = cs.measure(progress=lambda left, total: progress.append((left, total)))
        first_read = min(t for t, command in cs.transport.write_times if command.startswith(b"MEDR"))
    assert first_read >= 1.5 + 3  # nothing was sent before the second line
    np.testing.assert_array_equal(m.wavelengths, np.arange(380, 781))
    assert m.radiance.shape == (401,)
    np.testing.assert_allclose(m.radiance, RADIANCE, rtol=1e-4)
    np.testing.assert_allclose(m.XYZ, [126.20, 133.99, 113.34])
    assert m.Lv == pytest.approx(133.99)
    np.testing.assert_allclose(m.xy, [0.3379, 0.3587])
    assert m.colorimetry["T"] == 5303 and m.colorimetry["delta_uv"] == pytest.approx(0.0065)
    assert m.colorimetry["Pe10"] is None  # -9.9999e9: not computable
    assert set(m.colorimetry) == set(COLORIMETRIC_KEYS)
    assert m.integration_s == pytest.approx(0.859)
    assert m.nd_used is True
    assert m.measurement_time_s == 3
    assert progress[0] == (3.0, 3.0) and progress[-1] == (0.0, 3.0)
    remaining = [left for left, _ in progress]
    assert remaining == sorted(remaining, reverse=True) and len(remaining) >= 4  # about once a second
    with pytest.raises(ValueError):
        m.radiance[0] = 1.0  # results are immutable


def test_measure_with_float32_hex_spectra():
    exchanges = [(b"MEAS,1\r\n", measuring(2)), *readout(binary=True)]
    with expected_protocol(exchanges, spectral_format="float32") as cs:
        m = cs.measure()
    np.testing.assert_allclose(m.radiance, RADIANCE.astype(np.float32), rtol=0)


def test_spectral_block_parser_accepts_both_exponent_styles():
    for style in ("instrument", "python"):
        reply = parse_reply(spectral_reply(2, style=style).strip())
        np.testing.assert_allclose(parse_spectral_block(reply, 2, binary=False), RADIANCE[100:200], rtol=1e-4)


def test_spectral_block_with_wrong_count_is_a_protocol_error():
    reply = parse_reply(b"OK00," + b",".join([b"1.0e-3"] * 99))
    with pytest.raises(ProtocolError, match="expected 100"):
        parse_spectral_block(reply, 1, binary=False)
    with pytest.raises(ProtocolError, match="expected 101"):
        parse_spectral_block(parse_reply(spectral_reply(3).strip()), 4, binary=False)


def test_colorimetry_placeholders_become_none_and_nan():
    fields = ["-9.9999e9"] * 24
    fields[0], fields[1], fields[2], fields[3], fields[4] = "0.0000e+0", "0.0000", "0.0", "0.0", "0.0"
    values = parse_colorimetry(parse_reply(("OK00," + ",".join(fields)).encode()))
    assert values["x"] is None and values["T"] is None and values["Lv"] == 0.0
    exchanges = [(b"MEAS,1\r\n", b"OK00,242\r\nOK00\r\n"), *readout()[:4],
                 (b"MEDR,2,0,00\r\n", ("OK00," + ",".join(fields) + "\r\n").encode()),
                 (b"MEDR,0,0,1\r\n", f"OK00,{CONDITIONS}\r\n".encode())]  # fmt: skip
    with expected_protocol(exchanges) as cs:
        m = cs.measure()
    assert np.isnan(m.xy).all() and m.Lv == 0.0


@pytest.mark.parametrize("line", [1, 2])
def test_over_range_is_retried_once_with_the_nd_filter(line):
    first = [(1.0, b"ER10\r\n")] if line == 1 else measuring(2, end=b"ER10\r\n")
    exchanges = [
        (b"MEAS,1\r\n", first),
        (b"SPMR\r\n", b"OK00,0,0\r\n"),
        (b"SPMS,0,1\r\n", b"OK00\r\n"),
        (b"MEAS,1\r\n", measuring(2)),
        *readout(conditions="0,0,000100000,1,0,0,0,00"),
        (b"SPMS,0,0\r\n", b"OK00\r\n"),  # the previous speed mode, restored
    ]
    with expected_protocol(exchanges) as cs:
        m = cs.measure()
    assert m.nd_used is True


def test_over_range_twice_raises_and_restores_the_speed_mode():
    exchanges = [
        (b"MEAS,1\r\n", b"ER10\r\n"),
        (b"SPMR\r\n", b"OK00,3,000500000,0\r\n"),
        (b"SPMS,3,000500000,1\r\n", b"OK00\r\n"),
        (b"MEAS,1\r\n", b"ER10\r\n"),
        (b"SPMS,3,000500000,0\r\n", b"OK00\r\n"),
    ]
    with expected_protocol(exchanges) as cs:
        with pytest.raises(OverRangeError) as info:
            cs.measure()
    assert info.value.code == "ER10"
    assert "even with the internal ND filter on" in info.value.meaning
    assert "measuring angle" in info.value.advice


def test_over_range_with_the_nd_filter_already_on_is_not_retried():
    exchanges = [(b"MEAS,1\r\n", b"ER10\r\n"), (b"SPMR\r\n", b"OK00,0,1\r\n")]
    with expected_protocol(exchanges) as cs:
        with pytest.raises(OverRangeError):
            cs.measure()


@pytest.mark.parametrize(("code", "cls"), [("ER83", AngleKnobError), ("ER51", TemperatureError)])
def test_measure_error_on_the_first_line_sends_nothing_more(code, cls):
    with expected_protocol([(b"MEAS,1\r\n", f"{code}\r\n".encode())]) as cs:
        with pytest.raises(cls) as info:
            cs.measure()
    assert info.value.code == code


@pytest.mark.parametrize("as_callable", [False, True])
def test_cancel_sends_meas_0(as_callable):
    event = threading.Event()
    cancel = event.is_set if as_callable else event
    exchanges = [(b"MEAS,1\r\n", measuring(10)), (b"MEAS,0\r\n", b"OK00\r\n")]
    with expected_protocol(exchanges) as cs:
        with pytest.raises(MeasurementCancelled):
            cs.measure(progress=lambda left, total: event.set(), cancel=cancel)
        assert cs.transport.writes[-1] == b"MEAS,0\r\n"
        assert cs.transport.write_times[-1][0] < 1.0 + 10  # sent while measuring: the measurement stopped


def test_cancel_during_the_pre_measurement_skips_the_late_countdown():
    event = threading.Event()
    exchanges = [(b"MEAS,1\r\n", b""), (b"MEAS,0\r\n", b"OK00,004\r\nOK00\r\n")]
    with expected_protocol(exchanges) as cs:
        cs.transport.on_read = event.set
        with pytest.raises(MeasurementCancelled, match="pre-measurement"):
            cs.measure(cancel=event)


def test_cancel_before_start_sends_nothing():
    event = threading.Event()
    event.set()
    with expected_protocol([]) as cs:
        with pytest.raises(MeasurementCancelled):
            cs.measure(cancel=event)


def test_an_exception_in_progress_stops_the_instrument_and_propagates():
    def progress(left, total):
        raise KeyboardInterrupt

    exchanges = [(b"MEAS,1\r\n", b"OK00,010\r\n"), (b"MEAS,0\r\n", b"OK00\r\n")]
    with expected_protocol(exchanges) as cs:
        with pytest.raises(KeyboardInterrupt):
            cs.measure(progress=progress)


def test_a_garbled_countdown_stops_the_instrument():
    exchanges = [(b"MEAS,1\r\n", b"OK00,abc\r\n"), (b"MEAS,0\r\n", b"OK00\r\n")]
    with expected_protocol(exchanges) as cs:
        with pytest.raises(ProtocolError, match="countdown"):
            cs.measure()


def test_missing_second_line_times_out_after_ttt_plus_margin():
    exchanges = [(b"MEAS,1\r\n", [(0.5, b"OK00,005\r\n")]), (b"MEAS,0\r\n", b"OK00\r\n")]
    with expected_protocol(exchanges, timeout_s=1.0) as cs:
        with pytest.raises(CS2000Timeout) as info:
            cs.measure()
        assert cs.transport.clock.now >= 5 + 1.0  # waited ttt + margin, not less
        assert cs.transport.clock.now < 5 + 1.0 + 1.0 + 0.2
        assert cs.transport.write_times[-1][0] >= 0.5 + 5 + 1.0  # ttt + margin after the countdown line
    assert "MEAS,1" in str(info.value) and "end of the 5 s measurement" in str(info.value)


def test_no_reply_times_out_after_timeout_s():
    with expected_protocol([(b"IDDR\r\n", b"")], timeout_s=10.0) as cs:
        with pytest.raises(CS2000Timeout, match="IDDR"):
            cs.identify()
        assert 10.0 <= cs.transport.clock.now < 10.2


# ----------------------------------------------------------------------------- vanishing port


class VanishingTransport(FakeTransport):
    def read(self, n=1):
        raise serial.SerialException("device reports readiness to read but returned no data")


def test_port_vanishing_mid_read_is_a_clear_error():
    clock = FakeClock()
    transport = VanishingTransport([(b"IDDR\r\n", b"")], clock)
    transport.port = "/dev/ttyACM7"
    cs = CS2000(transport, clock=clock)
    with pytest.raises(PortVanishedError) as info:
        cs.identify()
    message = str(info.value)
    assert "/dev/ttyACM7" in message and "vanished" in message and "IDDR" in message
    assert "reconnect" in message.lower()


def test_port_vanishing_on_write_is_a_clear_error():
    class Broken(FakeTransport):
        def write(self, data):
            raise OSError(5, "Input/output error")

    cs = CS2000(Broken([], FakeClock()), clock=FakeClock())
    with pytest.raises(PortVanishedError, match="sending MEAS,1"):
        cs.measure()


# ----------------------------------------------------------------------------- discovery


def _port(device, vid=None, pid=None, description="n/a"):
    return SimpleNamespace(device=device, vid=vid, pid=pid, description=description, product=None)


def test_find_and_open_cs2000_ports(monkeypatch):
    ports = [_port("/dev/ttyS0"), _port("/dev/ttyACM1", 0x132B, 0x2104, "CS-2000"),
             _port("/dev/ttyUSB0", 0x0403, 0x6001, "FTDI")]  # fmt: skip
    monkeypatch.setattr(driver_module.list_ports, "comports", lambda: ports)
    assert find_cs2000_ports() == [("/dev/ttyACM1", "CS-2000")]
    opened = []
    monkeypatch.setattr(driver_module, "CS2000", lambda port, **kw: opened.append((port, kw)) or "driver")
    assert open_cs2000(timeout_s=12) == "driver"
    assert opened == [("/dev/ttyACM1", {"timeout_s": 12})]
    assert driver_module._is_usb_device("/dev/ttyACM1")
    assert not driver_module._is_usb_device("/dev/pts/3")


def test_open_cs2000_lists_candidates_when_ambiguous_or_absent(monkeypatch):
    two = [_port("/dev/ttyACM0", 0x132B, 0x2104, "CS-2000"), _port("/dev/ttyACM1", 0x132B, 0x2104, "CS-2000")]
    monkeypatch.setattr(driver_module.list_ports, "comports", lambda: two)
    with pytest.raises(PortSelectionError, match="/dev/ttyACM0.*/dev/ttyACM1") as info:
        open_cs2000()
    assert len(info.value.candidates) == 2
    monkeypatch.setattr(driver_module.list_ports, "comports", lambda: [_port("/dev/ttyS0")])
    with pytest.raises(PortSelectionError, match="no CS-2000.*/dev/ttyS0"):
        open_cs2000()


# ----------------------------------------------------------------------------- scripted timing


def test_the_fake_transport_refuses_a_command_while_a_line_is_due():
    clock = FakeClock()
    transport = FakeTransport([(b"MEAS,1\r\n", measuring(5)), (b"IDDR\r\n", IDDR_REPLY + b"\r\n")], clock)
    transport.write(b"MEAS,1\r\n")
    with pytest.raises(AssertionError, match=r"wrote b'IDDR\\r\\n' at t=0.00 s while .*OK00,005"):
        transport.write(b"IDDR\r\n")
    clock.now = 6.0  # both lines have come
    transport.write(b"IDDR\r\n")


def test_no_command_is_sent_before_the_second_line_of_a_long_measurement():
    exchanges = [(b"MEAS,1\r\n", measuring(30, pre_s=7.5)), *readout(), (b"IDDR\r\n", IDDR_REPLY + b"\r\n")]
    with expected_protocol(exchanges) as cs:  # the transport fails on any write while a line is due
        cs.measure()
        cs.identify()
        writes = cs.transport.write_times
    assert [command for _, command in writes][:2] == [b"MEAS,1\r\n", b"MEDR,1,0,1\r\n"]
    assert writes[1][0] >= 7.5 + 30


# ----------------------------------------------------------------------------- MEAS,0 acknowledgements


def test_an_error_answer_to_the_cancel_is_logged_and_the_cancel_still_stands(caplog):
    event = threading.Event()
    exchanges = [(b"MEAS,1\r\n", measuring(10)), (b"MEAS,0\r\n", b"ER17\r\n")]
    with caplog.at_level(logging.WARNING, logger="instruments.cs2000"):
        with expected_protocol(exchanges) as cs:
            with pytest.raises(MeasurementCancelled):
                cs.measure(progress=lambda left, total: event.set(), cancel=event)
    assert "MEAS,0 answered ER17" in caplog.text


def test_an_unacknowledged_stop_does_not_mask_the_timeout(caplog):
    exchanges = [(b"MEAS,1\r\n", [(0.5, b"OK00,002\r\n")]), (b"MEAS,0\r\n", b"")]
    with caplog.at_level(logging.WARNING, logger="instruments.cs2000"):
        with expected_protocol(exchanges, timeout_s=1.0) as cs:
            with pytest.raises(CS2000Timeout, match="end of the 2 s measurement"):
                cs.measure()
    assert "MEAS,0 got no clean acknowledgement" in caplog.text


# ----------------------------------------------------------------------------- not computable


def test_spectral_placeholders_become_nan():
    fields = [f"{v:.4e}" for v in RADIANCE[:100]]
    fields[0], fields[7], fields[99] = "-9.9999e9", "9.9999E+09", "-9.9999e+9"
    values = parse_spectral_block(parse_reply(("OK00," + ",".join(fields)).encode()), 1, binary=False)
    assert np.isnan(values[[0, 7, 99]]).all()
    finite = np.delete(np.arange(100), [0, 7, 99])
    np.testing.assert_allclose(values[finite], RADIANCE[finite], rtol=1e-4)
    hexes = [np.array(v, dtype=">f4").tobytes().hex().upper() for v in RADIANCE[100:200]]
    hexes[3] = np.array(-9.9999e9, dtype=">f4").tobytes().hex().upper()
    values = parse_spectral_block(parse_reply(("OK00," + ",".join(hexes)).encode()), 2, binary=True)
    assert np.isnan(values[3]) and np.isfinite(np.delete(values, 3)).all()


def test_a_measurement_with_a_not_computable_spectral_value_reads_it_as_nan():
    fields = spectral_reply(1).strip()[len(b"OK00,"):].split(b",")
    fields[0] = b"-9.9999e9"
    block = b"OK00," + b",".join(fields) + b"\r\n"
    exchanges = [(b"MEAS,1\r\n", measuring(2)), (b"MEDR,1,0,1\r\n", block), *readout()[1:]]
    with expected_protocol(exchanges) as cs:
        m = cs.measure()
    assert np.isnan(m.radiance[0]) and np.isfinite(m.radiance[1:]).all()
    np.testing.assert_allclose(m.radiance[1:], RADIANCE[1:], rtol=1e-4)
    np.testing.assert_allclose(m.XYZ, [126.20, 133.99, 113.34])  # the colorimetric values are kept


@pytest.mark.parametrize("bad", ["3A83126", "3A83126F0", "3A83126G", "0x3A8312"])
def test_a_float32_value_must_have_exactly_eight_hex_digits(bad):
    hexes = [np.array(v, dtype=">f4").tobytes().hex().upper() for v in RADIANCE[:100]]
    hexes[41] = bad
    raw = ("OK00," + ",".join(hexes)).encode()
    with pytest.raises(ProtocolError) as info:
        parse_spectral_block(parse_reply(raw), 1, binary=True)
    message = str(info.value)
    assert f"spectral value 42 is '{bad}'" in message and "8 hex digits" in message
    assert repr(raw[:60]) in message  # names the reply
    assert info.value.raw_reply == raw


# ----------------------------------------------------------------------------- remote mode fallbacks


def test_rmts_2_if_supported():
    with expected_protocol([(b"RMTS,2\r\n", b"OK00\r\n"), (b"RMTS,0\r\n", b"OK00\r\n")],
                           no_flash_write="if-supported") as cs:  # fmt: skip
        with cs:
            assert cs.remote_mode == 2
        assert cs.remote_mode == 0


def test_an_error_answer_to_rmts_2_falls_back_to_rmts_1(caplog):
    exchanges = [(b"RMTS,2\r\n", b"ER00\r\n"), (b"RMTS,1\r\n", b"OK00\r\n"), (b"RMTS,0\r\n", b"OK00\r\n")]
    with caplog.at_level(logging.INFO, logger="instruments.cs2000"):
        with expected_protocol(exchanges, no_flash_write="if-supported") as cs:
            with cs:
                assert cs.remote_mode == 1
    assert "RMTS,2 answered ER00" in caplog.text


def test_no_fallback_when_rmts_2_was_required_or_the_link_failed():
    with expected_protocol([(b"RMTS,2\r\n", b"ER00\r\n")], no_flash_write=True) as cs:
        with pytest.raises(CS2000Error, match="ER00"):
            with cs:
                pass
    with expected_protocol([(b"RMTS,2\r\n", b"")], no_flash_write="if-supported") as cs:
        with pytest.raises(CS2000Timeout, match="RMTS,2"):
            with cs:
                pass
    with pytest.raises(ValueError, match="no_flash_write"):
        CS2000(FakeTransport([], FakeClock()), no_flash_write="sometimes")


def test_a_failing_rmts_0_after_a_clean_block_is_only_a_warning(caplog):
    exchanges = [(b"RMTS,1\r\n", b"OK00\r\n"), (b"IDDR\r\n", IDDR_REPLY + b"\r\n"), (b"RMTS,0\r\n", b"ER99\r\n")]
    with caplog.at_level(logging.WARNING, logger="instruments.cs2000"):
        with expected_protocol(exchanges) as cs:
            with cs:
                assert cs.identify().serial == "10001234"
    assert "could not leave remote mode (RMTS,0)" in caplog.text and "ER99" in caplog.text


def test_a_failing_rmts_0_does_not_mask_the_blocks_own_error(caplog):
    exchanges = [(b"RMTS,1\r\n", b"OK00\r\n"), (b"IDDR\r\n", b"ER83\r\n"), (b"RMTS,0\r\n", b"ER99\r\n")]
    with caplog.at_level(logging.WARNING, logger="instruments.cs2000"):
        with expected_protocol(exchanges) as cs:
            with pytest.raises(AngleKnobError):
                with cs:
                    cs.identify()
    assert "ER99" in caplog.text
