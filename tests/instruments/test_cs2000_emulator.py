"""The CS-2000 emulator as a pure state machine, byte for byte."""

from __future__ import annotations

import logging

import colour
import numpy as np
import pytest

from instruments.cs2000 import (
    CS2000Emulator,
    ErrorFault,
    GarbageFault,
    TimeoutFault,
    VanishFault,
    measurement_timing,
    radiance_to_luminance,
)
from instruments.cs2000.emulator import LUMINANCE_RANGE_CD_M2, ND_TRANSMITTANCE

SHAPE = colour.SpectralShape(380, 780, 1)
CMFS_2 = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE)
CMFS_10 = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"].copy().align(SHAPE)
D65 = colour.SDS_ILLUMINANTS["D65"].copy().align(SHAPE).values


def radiance_for(luminance_cd_m2: float) -> np.ndarray:
    """A D65-shaped spectral radiance with the given luminance."""
    return D65 * luminance_cd_m2 / (683.0 * D65 @ CMFS_2.values[:, 1])


def make(luminance=80.0, time_scale=0.0, seed=1, **kwargs) -> CS2000Emulator:
    emulator = CS2000Emulator(lambda: radiance_for(luminance), time_scale=time_scale, seed=seed, **kwargs)
    assert emulator.feed(b"RMTS,1\r\n", 0.0) == b"OK00\r\n"
    return emulator


def fields(reply: bytes) -> list[str]:
    line = reply.strip(b"\r\n").decode()
    assert line.startswith("OK00,"), line
    return line.split(",")[1:]


# ----------------------------------------------------------------------------- framing and remote


def test_commands_before_remote_mode_are_refused():
    emulator = CS2000Emulator(lambda: radiance_for(10), time_scale=0)
    assert emulator.feed(b"IDDR\r\n", 0.0) == b"ER00\r\n"
    assert emulator.feed(b"MEAS,1\r\n", 0.0) == b"ER00\r\n"
    assert emulator.feed(b"RMTS,1\r\n", 0.0) == b"OK00\r\n"
    assert emulator.remote_mode == 1
    assert emulator.feed(b"RMTS,0\r\n", 0.0) == b"OK00\r\n"
    assert emulator.feed(b"IDDR\r\n", 0.0) == b"ER00\r\n"
    assert emulator.feed(b"RMTS,2\r\n", 0.0) == b"OK00\r\n" and emulator.remote_mode == 2
    assert emulator.feed(b"RMTS,7\r\n", 0.0) == b"ER17\r\n"
    assert emulator.feed(b"RMTS\r\n", 0.0) == b"ER00\r\n"


def test_identify_pads_the_name_to_nine():
    assert make().feed(b"IDDR\r\n", 0.0) == b"OK00,CS-2000  ,1,10001234\r\n"
    assert make(model=2, serial_number="20005678").feed(b"IDDR\r\n", 0) == b"OK00,CS-2000A ,2,20005678\r\n"


@pytest.mark.parametrize("terminator", [b"\r", b"\n", b"\r\n"])
def test_the_reply_uses_the_command_terminator(terminator):
    assert make().feed(b"STSR" + terminator, 0.0) == b"OK00,0" + terminator


def test_crlf_split_across_feeds_gives_one_reply():
    emulator = make()
    assert emulator.feed(b"STSR\r", 0.0) == b"OK00,0\r"
    assert emulator.feed(b"\n", 0.0) == b""
    assert emulator.feed(b"ST", 0.0) == b""
    assert emulator.feed(b"SR\n", 0.0) == b"OK00,0\n"


def test_several_commands_in_one_chunk_are_answered_in_order():
    assert make(angle=2).feed(b"STSR\r\nSCMR\r\nNOPE\r\n", 0.0) == b"OK00,2\r\nOK00,0\r\nER00\r\n"


def test_unknown_commands_and_bad_parameter_counts():
    emulator = make()
    assert emulator.feed(b"HELLO\r\n", 0.0) == b"ER00\r\n"
    assert emulator.feed(b"IDDR,1\r\n", 0.0) == b"ER00\r\n"
    assert emulator.feed(b"MEDR,1,0\r\n", 0.0) == b"ER00\r\n"
    assert emulator.feed(b"MEAS\r\n", 0.0) == b"ER00\r\n"
    assert emulator.feed(b"MEAS,5\r\n", 0.0) == b"ER17\r\n"


# ----------------------------------------------------------------------------- settings


@pytest.mark.parametrize(
    ("command", "readback"),
    [
        (b"SPMS,0,0", b"OK00,0,0"),
        (b"SPMS,1,2", b"OK00,1,2"),
        (b"SPMS,2,08,1", b"OK00,2,08,1"),
        (b"SPMS,4,16,0", b"OK00,4,16,0"),
        (b"SPMS,3,000500000,1", b"OK00,3,000500000,1"),
    ],
)
def test_speed_mode_round_trip(command, readback):
    emulator = make()
    assert emulator.feed(command + b"\r\n", 0.0) == b"OK00\r\n"
    assert emulator.feed(b"SPMR\r\n", 0.0) == readback + b"\r\n"


@pytest.mark.parametrize(
    ("command", "error"),
    [
        (b"SPMS,5,0", b"ER17"), (b"SPMS,0,3", b"ER17"), (b"SPMS,2,17,0", b"ER17"),
        (b"SPMS,3,000004000,0", b"ER17"), (b"SPMS,0", b"ER00"), (b"SPMS,2,0", b"ER00"),
        (b"SCMS,1,1000", b"ER17"), (b"SCMS,1", b"ER00"), (b"SCMS,3", b"ER17"), (b"SCMS,0,6000", b"ER00"),
    ],
)  # fmt: skip
def test_bad_settings_are_refused(command, error):
    emulator = make()
    assert emulator.feed(command + b"\r\n", 0.0) == error + b"\r\n"
    assert emulator.feed(b"SPMR\r\n", 0.0) == b"OK00,0,2\r\n"  # unchanged default
    assert emulator.feed(b"SCMR\r\n", 0.0) == b"OK00,0\r\n"


def test_sync_mode_round_trip():
    emulator = make()
    assert emulator.feed(b"SCMS,1,9000\r\n", 0.0) == b"OK00\r\n"
    assert emulator.feed(b"SCMR\r\n", 0.0) == b"OK00,1,9000\r\n"
    assert emulator.feed(b"SCMS,2\r\n", 0.0) == b"OK00\r\n"
    assert emulator.feed(b"SCMR\r\n", 0.0) == b"OK00,2\r\n"


# ----------------------------------------------------------------------------- measuring and timing


def test_medr_before_any_measurement_is_no_data():
    emulator = make()
    for command in (b"MEDR,1,0,1", b"MEDR,1,1,4", b"MEDR,2,0,00", b"MEDR,0,0,1"):
        assert emulator.feed(command + b"\r\n", 0.0) == b"ER20\r\n"
    assert emulator.feed(b"MEDR,1,0,5\r\n", 0.0) == b"ER17\r\n"


def test_measurement_timeline_at_real_time_scale():
    emulator = make(luminance=200.0, time_scale=1.0)
    assert emulator.feed(b"MEAS,1\r\n", 10.0) == b""  # pre-measurement runs
    assert emulator.measuring
    assert emulator.poll(10.99) == b""
    assert emulator.feed(b"IDDR\r\n", 10.5) == b"ER02\r\n"
    assert emulator.feed(b"MEAS,1\r\n", 10.5) == b"ER17\r\n"
    assert emulator.poll(11.0) == b"OK00,002\r\n"  # 1 s pre-measurement, 2 s to go
    assert emulator.next_event_time() == pytest.approx(13.0)
    assert emulator.feed(b"MEDR,2,0,00\r\n", 12.0) == b"ER02\r\n"
    assert emulator.poll(12.99) == b""
    assert emulator.poll(13.0) == b"OK00\r\n"  # the unsolicited second line
    assert not emulator.measuring
    assert len(fields(emulator.feed(b"MEDR,1,0,1\r\n", 13.1))) == 100


def test_time_scale_zero_answers_both_lines_at_once():
    assert make(time_scale=0).feed(b"MEAS,1\r\n", 0.0) == b"OK00,002\r\nOK00\r\n"


def test_time_scale_shrinks_every_wait():
    emulator = make(luminance=0.01, time_scale=0.01)
    assert emulator.feed(b"MEAS,1\r\n", 0.0) == b""
    first = emulator.poll(0.2)
    countdown = int(fields(first)[0])
    assert 30 < countdown < 242
    assert emulator.poll(0.2 + countdown * 0.01) == b"OK00\r\n"


def _timing(luminance, speed=b"SPMS,0,2"):
    emulator = make(luminance=luminance, time_scale=1.0)
    assert emulator.feed(speed + b"\r\n", 0.0) == b"OK00\r\n"
    emulator.feed(b"MEAS,1\r\n", 0.0)
    pre = emulator.next_event_time()
    countdown = int(fields(emulator.poll(pre))[0])
    return pre, countdown


def test_integration_grows_at_low_luminance_up_to_the_limit():
    bright_pre, bright = _timing(500.0)
    mid_pre, mid = _timing(1.0)
    dark_pre, dark = _timing(0.01)
    floor_pre, floor = _timing(0.003)
    below_pre, below = _timing(0.0005)
    assert (bright_pre, bright) == (1.0, 2)
    assert bright < mid < dark < floor == below == 242
    assert 1.0 < mid_pre < dark_pre < floor_pre == pytest.approx(10.0)
    assert below_pre == pytest.approx(10.0)
    assert _timing(0.01, b"SPMS,1,2")[1] < dark  # fast mode is shorter
    assert _timing(0.003, b"SPMS,1,2")[1] == 16
    assert _timing(0.01, b"SPMS,3,002000000,2") == (1.0, 5)  # manual: 2 × 2 s + 1 s
    assert _timing(0.01, b"SPMS,2,10,2") == (1.0, 21)


@pytest.mark.parametrize(("luminance", "speed", "mode", "integration_s"), [
    (500.0, b"SPMS,0,2", 0, None), (1.0, b"SPMS,0,2", 0, None), (0.01, b"SPMS,0,2", 0, None),
    (0.0005, b"SPMS,0,2", 0, None), (0.01, b"SPMS,1,2", 1, None), (0.01, b"SPMS,3,002000000,2", 3, 2.0),
    (0.01, b"SPMS,2,10,2", 2, 10.0), (3.0, b"SPMS,4,03,2", 4, 3.0),
])  # fmt: skip
def test_measurement_timing_is_what_the_emulator_does(luminance, speed, mode, integration_s):
    pre, countdown = _timing(luminance, speed)
    timing = measurement_timing(radiance_to_luminance(radiance_for(luminance)), mode, integration_s)
    assert (timing.pre_measurement_s, timing.measurement_s) == (pre, countdown)
    assert timing.duration_s == pre + countdown
    emulator = make(luminance=luminance, time_scale=1.0)
    emulator.feed(speed + b"\r\n", 0.0)
    emulator.feed(b"MEAS,1\r\n", 0.0)
    emulator.poll(pre)
    assert emulator.next_event_time() == timing.duration_s
    emulator.poll(timing.duration_s)
    conditions = fields(emulator.feed(b"MEDR,0,0,1\r\n", timing.duration_s))
    assert int(conditions[2]) == round(timing.integration_s * 1e6)


def test_measurement_timing_scales_the_floor_with_the_angle():
    floor_01 = LUMINANCE_RANGE_CD_M2[2][0]
    assert measurement_timing(floor_01, angle=2).measurement_s == 242
    assert measurement_timing(floor_01, angle=0).measurement_s < 242
    assert radiance_to_luminance(radiance_for(42.0)) == pytest.approx(42.0, rel=1e-9)
    with pytest.raises(ValueError, match="needs integration_s"):
        measurement_timing(1.0, mode=3)


def test_cancel_with_meas_0():
    emulator = make(time_scale=1.0)
    emulator.feed(b"MEAS,1\r\n", 0.0)
    assert emulator.poll(emulator.next_event_time()) == b"OK00,002\r\n"
    assert emulator.feed(b"MEAS,0\r\n", 1.5) == b"OK00\r\n"
    assert not emulator.measuring
    assert emulator.poll(100.0) == b""  # no second line after a cancel
    assert emulator.feed(b"MEDR,2,0,00\r\n", 100.0) == b"ER20\r\n"
    assert emulator.feed(b"MEAS,0\r\n", 100.0) == b"OK00\r\n"  # harmless when idle


# ----------------------------------------------------------------------------- data


def _measure(emulator) -> None:
    assert emulator.feed(b"MEAS,1\r\n", 0.0).endswith(b"OK00\r\n")


def _spectrum(emulator, form=0) -> np.ndarray:
    values = []
    for block in (1, 2, 3, 4):
        values += fields(emulator.feed(f"MEDR,1,{form},{block}\r\n".encode(), 0.0))
    if form:
        return np.frombuffer(bytes.fromhex("".join(values)), dtype=">f4").astype(float)
    return np.array([float(v) for v in values])


def test_spectral_blocks_have_the_documented_sizes_and_formats():
    emulator = make()
    _measure(emulator)
    sizes = [len(fields(emulator.feed(f"MEDR,1,0,{b}\r\n".encode(), 0.0))) for b in (1, 2, 3, 4)]
    assert sizes == [100, 100, 100, 101]
    first = fields(emulator.feed(b"MEDR,1,0,1\r\n", 0.0))[0]
    assert first[1] == "." and "e-" in first and len(first.split("e")[0]) == 6  # 1.2345e-4
    ascii_values, float_values = _spectrum(emulator, 0), _spectrum(emulator, 1)
    np.testing.assert_allclose(ascii_values, float_values, rtol=6e-5)
    assert all(len(v) == 8 for v in fields(emulator.feed(b"MEDR,1,1,4\r\n", 0.0)))


def test_measured_spectrum_is_the_source_plus_small_noise():
    truth = radiance_for(80.0)
    emulator = make(luminance=80.0)
    _measure(emulator)
    ratio = _spectrum(emulator, 1) / truth
    assert 0.001 < np.std(ratio) < 0.004  # ~0.2 % multiplicative noise
    assert abs(np.mean(ratio) - 1) < 0.001


def test_noise_is_seeded():
    a, b, c = make(seed=7), make(seed=7), make(seed=8)
    for emulator in (a, b, c):
        _measure(emulator)
    assert a.feed(b"MEDR,1,1,2\r\n", 0) == b.feed(b"MEDR,1,1,2\r\n", 0) != c.feed(b"MEDR,1,1,2\r\n", 0)


def test_colorimetry_matches_colour_science():
    emulator = make(luminance=120.0)
    _measure(emulator)
    spectrum = _spectrum(emulator, 1)
    values = fields(emulator.feed(b"MEDR,2,0,00\r\n", 0.0))
    assert len(values) == 24
    sd = colour.SpectralDistribution(spectrum, SHAPE.wavelengths)
    XYZ = colour.sd_to_XYZ(sd, CMFS_2, k=683, method="Integration")
    XYZ10 = colour.sd_to_XYZ(sd, CMFS_10, k=683, method="Integration")
    le, lv, X, Y, Z, x, y, up, vp, T, duv = (float(v) for v in values[:11])
    assert le == pytest.approx(spectrum.sum(), rel=1e-4)
    np.testing.assert_allclose([X, Y, Z], XYZ, rtol=1e-4)
    assert lv == pytest.approx(XYZ[1], rel=1e-4) and lv == pytest.approx(120.0, rel=0.01)
    np.testing.assert_allclose([x, y], colour.XYZ_to_xy(XYZ), atol=1e-4)
    np.testing.assert_allclose([up, vp], colour.xy_to_Luv_uv(colour.XYZ_to_xy(XYZ)), atol=1e-4)
    assert T == pytest.approx(6504, abs=15) and values[9].startswith(" ")  # space-padded
    assert duv == pytest.approx(0.0032, abs=5e-4)
    np.testing.assert_allclose([float(v) for v in values[13:16]], XYZ10, rtol=1e-4)


def test_black_gives_not_computable_placeholders():
    emulator = CS2000Emulator(lambda: np.zeros(401), time_scale=0, seed=1, noise_floor=0.0)
    emulator.feed(b"RMTS,1\r\n", 0.0)
    _measure(emulator)
    values = fields(emulator.feed(b"MEDR,2,0,00\r\n", 0.0))
    assert values[5:13] == ["-9.9999e9"] * 8
    assert values[16:24] == ["-9.9999e9"] * 8


def test_conditions_report_speed_sync_integration_nd_and_angle():
    emulator = make(luminance=80.0, angle=1)
    emulator.feed(b"SPMS,3,000250000,1\r\nSCMS,1,9000\r\n", 0.0)
    _measure(emulator)
    assert emulator.feed(b"MEDR,0,0,1\r\n", 0.0) == b"OK00,3,1,000250000,1,0,0,1,00\r\n"


# ----------------------------------------------------------------------------- over range


def test_over_range_depends_on_the_nd_filter():
    limit_off = LUMINANCE_RANGE_CD_M2[0][1] * ND_TRANSMITTANCE
    bright = make(luminance=limit_off * 2)
    bright.feed(b"SPMS,0,0\r\n", 0.0)
    assert bright.feed(b"MEAS,1\r\n", 0.0) == b"ER10\r\n"
    assert not bright.measuring
    assert bright.feed(b"MEDR,2,0,00\r\n", 0.0) == b"ER20\r\n"
    bright.feed(b"SPMS,0,1\r\n", 0.0)
    _measure(bright)
    assert fields(bright.feed(b"MEDR,0,0,1\r\n", 0.0))[3] == "1"
    bright.feed(b"SPMS,0,2\r\n", 0.0)  # auto switches the filter in
    _measure(bright)
    assert fields(bright.feed(b"MEDR,0,0,1\r\n", 0.0))[3] == "1"
    too_bright = make(luminance=LUMINANCE_RANGE_CD_M2[0][1] * 1.5)
    too_bright.feed(b"SPMS,0,1\r\n", 0.0)
    assert too_bright.feed(b"MEAS,1\r\n", 0.0) == b"ER10\r\n"
    dim = make(luminance=80.0)
    dim.feed(b"SPMS,0,2\r\n", 0.0)
    _measure(dim)
    assert fields(dim.feed(b"MEDR,0,0,1\r\n", 0.0))[3] == "0"


def test_a_failing_radiance_source_answers_er99_and_logs(caplog):
    emulator = CS2000Emulator(lambda: np.zeros(10), time_scale=0)
    emulator.feed(b"RMTS,1\r\n", 0.0)
    with caplog.at_level(logging.ERROR):
        assert emulator.feed(b"MEAS,1\r\n", 0.0) == b"ER99\r\n"
    assert "401" in caplog.text


# ----------------------------------------------------------------------------- faults


def test_error_fault_on_the_nth_matching_command():
    emulator = make(faults=[ErrorFault("ER51", command="STSR", nth=2)])
    assert emulator.feed(b"STSR\r\n", 0.0) == b"OK00,0\r\n"
    assert emulator.feed(b"IDDR\r\n", 0.0).startswith(b"OK00")
    assert emulator.feed(b"STSR\r\n", 0.0) == b"ER51\r\n"
    assert emulator.feed(b"STSR\r\n", 0.0) == b"OK00,0\r\n"  # one-shot


def test_error_fault_counts_from_injection_and_any_command():
    emulator = make()
    emulator.feed(b"STSR\r\n", 0.0)
    emulator.inject(ErrorFault("ER83"))
    assert emulator.feed(b"MEAS,1\r\n", 0.0) == b"ER83\r\n"
    assert not emulator.measuring


def test_error_fault_on_the_end_of_measurement_line():
    emulator = make(faults=[ErrorFault("ER71", command="MEAS,1", line=2)])
    assert emulator.feed(b"MEAS,1\r\n", 0.0) == b"OK00,002\r\nER71\r\n"
    assert emulator.feed(b"MEDR,2,0,00\r\n", 0.0) == b"ER20\r\n"


def test_timeout_fault_drops_the_second_line_but_keeps_the_data():
    emulator = make(time_scale=1.0, faults=[TimeoutFault()])
    emulator.feed(b"MEAS,1\r\n", 0.0)
    assert emulator.poll(emulator.next_event_time()) == b"OK00,002\r\n"
    assert emulator.poll(50.0) == b""
    assert not emulator.measuring
    assert emulator.feed(b"MEDR,0,0,1\r\n", 50.0).startswith(b"OK00,")


def test_timeout_fault_on_an_ordinary_command_loses_it():
    emulator = make(faults=[TimeoutFault(command="IDDR")])
    assert emulator.feed(b"IDDR\r\n", 0.0) == b""
    assert emulator.feed(b"IDDR\r\n", 0.0).startswith(b"OK00")


def test_garbage_fault_prefixes_the_reply():
    emulator = make(faults=[GarbageFault(b"\xff\x00junk", command="MEAS")])
    assert emulator.feed(b"MEAS,1\r\n", 0.0) == b"\xff\x00junkOK00,002\r\nOK00\r\n"
    assert emulator.feed(b"STSR\r\n", 0.0) == b"OK00,0\r\n"


def test_vanish_fault_silences_the_emulator():
    emulator = make(faults=[VanishFault(command="MEDR", nth=2)])
    _measure(emulator)
    assert emulator.feed(b"MEDR,1,0,1\r\n", 0.0).startswith(b"OK00")
    assert emulator.feed(b"MEDR,1,0,2\r\n", 0.0) == b""
    assert emulator.vanished
    assert emulator.feed(b"IDDR\r\n", 0.0) == b""
    assert emulator.received[-2:] == ["MEDR,1,0,1", "MEDR,1,0,2"]


def test_fault_arguments_are_checked():
    with pytest.raises(ValueError):
        ErrorFault("E10")
    with pytest.raises(ValueError):
        ErrorFault("ER10", line=3)
    with pytest.raises(ValueError):
        VanishFault(nth=0)
    with pytest.raises(TypeError):
        make().inject("ER10")
