"""The APL library's pieces: session columns, load, curve, prediction input, readers' dispatch, errors."""

import numpy as np
import pytest

from tests.apl.generator import generate_session
from workbench.apl import (AplCurve, ChannelTransfer, apl_curve_from_json, channel_transfer,
                           detect_apl_dependence, evaluate_apl_holdout, fit_apl_curve, frame_load,
                           predict_XYZ_on_surround, read_predict_rows, reference_load)
from workbench.errors import InputError, SpectrumFileError
from workbench.session import Session, read_session_csv, write_session_csv


def _full_field_session():
    rgb = np.array([[255, 255, 255], [128, 128, 128], [255, 0, 0]], dtype=float)
    return Session(kind=["white", "grey", "ramp-r"], rgb=rgb, XYZ=rgb / 2.55 + 1)


def test_session_csv_round_trips_window_and_surround(tmp_path):
    session = generate_session(0.2, 1)
    path = write_session_csv(session, tmp_path / "s.csv")
    header = path.read_text().splitlines()[0].split(",")
    assert header[7:11] == ["window", "sr", "sg", "sb"]
    back = read_session_csv(path)
    assert np.allclose(back.window, session.window) and np.allclose(back.surround, session.surround)
    assert back.has_surround_data and back.subset(back.window < 1).window.max() < 1


def test_a_session_without_the_columns_is_full_field_on_black(tmp_path):
    session = _full_field_session()
    path = write_session_csv(session, tmp_path / "s.csv")
    assert "window" not in path.read_text().splitlines()[0]
    back = read_session_csv(path)
    assert back.window is None and not back.has_surround_data
    assert np.all(back.window_or_full == 1) and np.all(back.surround_or_black == 0)
    test = detect_apl_dependence(back, 0.002)
    assert not test.testable and test.z == 0 and "not testable" in test.evidence
    with pytest.raises(InputError, match="two different frames"):
        fit_apl_curve(back)


@pytest.mark.parametrize("row, problem", [
    ("white,255,255,255,1,1,1,0,0,0,0", "window 0 outside"),
    ("white,255,255,255,1,1,1,0.5,0,300,0", "surround DAC values"),
])
def test_bad_window_or_surround_values_name_the_line(tmp_path, row, problem):
    path = tmp_path / "s.csv"
    path.write_text("kind,r,g,b,X,Y,Z,window,sr,sg,sb\n" + row + "\n")
    with pytest.raises(SpectrumFileError, match=problem) as caught:
        read_session_csv(path)
    assert ":2" in str(caught.value) or "line 2" in str(caught.value)


def test_a_surround_needs_all_three_columns(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("kind,r,g,b,X,Y,Z,sr\nwhite,255,255,255,1,1,1,0\n")
    with pytest.raises(SpectrumFileError, match="sr,sg,sb"):
        read_session_csv(path)


def test_the_load_of_frames():
    transfer = ChannelTransfer("power", (2.0, 2.0, 2.0))
    white = [[255, 255, 255]]
    assert frame_load(white, [1.0], [[0, 0, 0]], transfer)[0] == pytest.approx(1.0)
    assert frame_load(white, [0.25], [[0, 0, 0]], transfer)[0] == pytest.approx(0.25)
    # a black window on a white surround carries the surround's load
    assert frame_load([[0, 0, 0]], [0.25], [[255, 255, 255]], transfer)[0] == pytest.approx(0.75)
    assert frame_load([[255, 0, 0]], [1.0], [[0, 0, 0]], transfer, (0.5, 0.25, 0.25))[0] == pytest.approx(0.5)
    assert np.allclose(reference_load([[128, 128, 128]], transfer), (128 / 255) ** 2)
    pq = channel_transfer("pq", peak_cd_m2=1000.0)
    assert pq.linear([[255, 255, 255]])[0, 0] == 1.0  # 10 000 cd/m² saturates at the peak
    with pytest.raises(InputError, match="power, pq"):
        channel_transfer("srgb")
    with pytest.raises(InputError, match="sum to 1"):
        frame_load(white, [1.0], [[0, 0, 0]], transfer, (0.5, 0.5, 0.5))


def test_the_curve_is_one_without_load_and_scales_full_field_predictions():
    curve = AplCurve(0.2, 4.0, 0.5)
    assert curve.gain(0.0) == pytest.approx(1.0)
    assert curve.gain(10.0) == pytest.approx((0.2 / 10.0) ** 0.5, rel=1e-3)
    rgb = np.array([[255, 255, 255], [255, 255, 255]])
    relative = curve.relative_gain(rgb, [1.0, 0.05], [[0, 0, 0], [0, 0, 0]])
    assert relative[0] == pytest.approx(1.0) and relative[1] > 1.3  # a small window escapes the limit
    assert apl_curve_from_json(curve.to_json()) == curve
    with pytest.raises(InputError, match="knee"):
        apl_curve_from_json({"sharpness": 1})


@pytest.mark.parametrize("key, value, message", [("method", "srgb", "unknown channel transfer 'srgb'"),
                                                 ("gammas", [2.2, 2.2], "2 transfer gammas")])
def test_an_apl_block_with_a_transfer_that_cannot_be_evaluated_is_refused_by_name(key, value, message):
    from workbench.profile import ProfileError, check_apl_block

    block = AplCurve(0.2, 4.0, 0.5).to_json()
    block["transfer"][key] = value
    with pytest.raises(InputError, match=message):
        apl_curve_from_json(block)
    with pytest.raises(ProfileError, match=message):  # not a KeyError or a broadcasting ValueError
        check_apl_block(block)


def test_predict_reads_the_optional_columns_by_name_or_position():
    rows = read_predict_rows("R,G,B,Window,SR,SG,SB\n255,255,255,0.1,0,0,0\n10,20,30,1,5,5,5\n")
    assert np.allclose(rows.window, [0.1, 1.0]) and np.allclose(rows.surround[1], 5)
    rows = read_predict_rows("255,255,255\n255,255,255,0.5\n1,2,3,0.5,9,9,9\n")
    assert np.allclose(rows.window, [1.0, 0.5, 0.5]) and np.allclose(rows.surround[2], 9)
    assert read_predict_rows("r,g,b\n1,2,3\n").full_field
    for bad, message in (("255,255,255,0\n", "window 0 outside"), ("1,2\n", "need r,g,b"),
                         ("r,g,b,sr\n1,2,3,4\n", "sr,sg,sb"), ("", "no r,g,b rows"),
                         ("1,2,3,0.5,7\n", "all of sr,sg,sb"), ("300,0,0\n", "outside 0..255")):
        with pytest.raises(InputError, match=message):
            read_predict_rows(bad)


def test_predict_needs_an_apl_curve_for_windows():
    model = lambda rgb: np.asarray(rgb, dtype=float) / 2.55  # noqa: E731
    full = read_predict_rows("255,255,255\n")
    assert np.allclose(predict_XYZ_on_surround(model, full), 100.0)
    windowed = read_predict_rows("255,255,255,0.05\n")
    with pytest.raises(InputError, match="no APL curve"):
        predict_XYZ_on_surround(model, windowed)
    curve = fit_apl_curve(generate_session(0.3, 3))
    brighter = predict_XYZ_on_surround(model, windowed, curve)
    assert brighter[0, 1] > 100.0 * 1.2


def test_detector_input_errors():
    with pytest.raises(InputError, match="relative_noise"):
        detect_apl_dependence(generate_session(0.2, 1), 0.0)


def test_holdout_needs_two_conditions():
    session = generate_session(0.2, 1)
    with pytest.raises(InputError, match="can be held out"):
        evaluate_apl_holdout(session, np.array(["same"] * len(session), dtype=object), "nothing")


def test_read_session_still_reads_a_psychtoolbox_mat_and_other_formats():
    import os
    from pathlib import Path

    from workbench.session_readers import read_session

    real = Path(os.environ.get("VR_WORKBENCH_SHARED", Path(__file__).resolve().parents[3] / "shared")
                ) / "data" / "real"
    if not real.is_dir():
        pytest.skip(f"the shared real display data is not at {real}")
    assert read_session(real / "sony-og-ptb-cal.mat").metadata["format"] == "psychtoolbox"
    assert read_session(real / "dell-up2516d-displaycal.ti3").window is None


def test_diagnose_apl_in_one_call():
    import json

    from workbench.apl import diagnose_apl, full_field_rows

    session = generate_session(0.3, 5)
    result = diagnose_apl(session, 0.002)
    assert result.test.z > 5 and result.curve is not None
    assert {h.by for h in result.holdouts} == {"window size", "surround level"}
    note = result.closing_note()
    assert note.startswith("apl-dependence: ") and "leave one window size out" in note
    json.dumps(result.to_json())
    assert full_field_rows(session).sum() == np.sum(session.window == 1)
    clean = diagnose_apl(_full_field_session(), 0.002)
    assert clean.curve is None and clean.holdouts == () and "not testable" in clean.closing_note()
    json.dumps(clean.to_json())


def test_a_short_row_in_a_colorimeter_csv_is_refused_naming_its_line(tmp_path):
    from workbench.session_readers import read_session

    path = tmp_path / "measure_Desktop_010_patch.csv"
    path.write_text("X,Y,Z\n1,2,3\n4,5\n")
    with pytest.raises(SpectrumFileError, match="line 3.*not three numbers"):
        read_session(path)
