"""The two real OLED data sets: read through read_session, apl-dependence found, the curve held out."""

import os
from pathlib import Path

import numpy as np
import pytest

from workbench.apl import apl_fold_labels, detect_apl_dependence, evaluate_apl_holdout, fit_apl_curve
from workbench.session_readers import read_session

REAL = Path(os.environ.get("VR_WORKBENCH_SHARED", Path(__file__).resolve().parents[3] / "shared")
            ) / "data" / "real" / "oled-apl"
pytestmark = pytest.mark.skipif(
    not REAL.is_dir(), reason=f"the shared real OLED data is not at {REAL} "
                              "(set VR_WORKBENCH_SHARED to the shared/ folder)")

INSTRUMENT_NOISE = 0.005  # a conservative repeatability for a PR-650 or a colorimeter (0.5 % of luminance)


@pytest.fixture(scope="module")
def samsung():
    return read_session(REAL / "SamsungOLED_calib_2014-09-29.mat")


@pytest.fixture(scope="module")
def colorchecker():
    return read_session(REAL / "AW3225QF")


def test_samsung_conditions_are_read_with_their_load(samsung):
    assert len(samsung) == 132
    assert samsung.has_surround_data
    assert np.allclose(samsung.window, 100 * 100 / (1920 * 1080))
    white = samsung.rgb[:, 0] == 255
    # the full-white target drops about 21 % as the stabilizer goes 0 -> 0.9 (smallest bias square)
    stabilizer = samsung.metadata["apl_folds"]["stabilizer level"]
    bias = samsung.metadata["apl_folds"]["bias size"]
    small = bias == "bias 100 px"
    low = samsung.XYZ[white & small & (stabilizer == "stabilizer 0"), 1][0]
    high = samsung.XYZ[white & small & (stabilizer == "stabilizer 0.9"), 1][0]
    assert 1 - high / low == pytest.approx(0.19, abs=0.03)
    # more load on the surround, less light from the same target
    order = np.argsort(samsung.surround[white, 0])
    assert samsung.XYZ[white, 1][order][0] > samsung.XYZ[white, 1][order][-1]


def test_samsung_apl_dependence_is_found_and_the_curve_beats_no_load_term(samsung):
    test = detect_apl_dependence(samsung, INSTRUMENT_NOISE)
    assert test.z > 20 and test.impact_dE00 > 3, test.evidence
    for by, labels in apl_fold_labels(samsung).items():
        score = evaluate_apl_holdout(samsung, labels, by)
        assert score.luminance_error_pct < 0.8 * score.luminance_error_pct_without, score.one_line()
        assert score.dE00 < score.dE00_without, score.one_line()


def test_aw3225qf_colorchecker_windows(colorchecker):
    assert len(colorchecker) == 18 * 25
    assert set(np.round(colorchecker.window, 2)) == {0.03, 0.1, 0.2, 0.5, 1.0}
    test = detect_apl_dependence(colorchecker, INSTRUMENT_NOISE)
    assert test.z > 20, test.evidence
    score = evaluate_apl_holdout(colorchecker, apl_fold_labels(colorchecker)["window size"], "window size")
    assert score.luminance_error_pct < 0.3 * score.luminance_error_pct_without, score.one_line()
    assert score.dE00 < 2.0, score.one_line()


def test_aw3225qf_white_windows_peak_preset_with_noise_from_its_repeats():
    session = read_session(REAL / "AW3225QF" / "measure_HDR_Peak_1000_003_patch.csv")
    assert len(session) == 2 * 5 * 64  # every window size, and its repeat
    blocks = session.XYZ[:, 1].reshape(10, 64)  # per window size: the series, then its repeat
    first, repeat = blocks[0::2].ravel(), blocks[1::2].ravel()
    bright = first > 0.02 * first.max()
    noise = float(np.std(np.log(repeat[bright] / first[bright])) / np.sqrt(2))
    assert 0 < noise < 0.05
    test = detect_apl_dependence(session, noise)
    assert test.z > 20, test.evidence
    curve = fit_apl_curve(session)
    assert curve.gain(1.0) / curve.gain(0.0) < 0.5  # 1025 cd/m² in a 3 % window, about 250 full field


def test_aw3225qf_custom_preset_shows_no_limiting():
    session = read_session(REAL / "AW3225QF" / "measure_Custom_Color_HDR_020_patch.csv")
    test = detect_apl_dependence(session, INSTRUMENT_NOISE)
    assert abs(test.statistic) < 0.01, test.evidence
    assert abs(test.z) < 3, test.evidence


@pytest.mark.parametrize("name", ["SamsungOLED_calib_2014-09-29.mat", "AW3225QF",
                                  "AW3225QF/cc_measure_lumi-0100_win-003.csv"])
def test_diagnose_names_apl_dependence_with_the_curves_held_out_error(name, capsys):
    from workbench.cli import main

    assert main(["diagnose", str(REAL / name)]) == 0
    out = capsys.readouterr().out
    assert "finding 1 apl-dependence" in out
    assert "untested  tone-curve-shape: no display model" in out
    held = [line for line in out.splitlines() if line.startswith("held out  leave one")]
    assert held and all("% of luminance" in line and "ΔE00 mean" in line for line in held)


def test_diagnose_will_not_export_a_profile_without_a_display_model(tmp_path, capsys):
    from workbench.cli import main

    assert main(["diagnose", str(REAL / "AW3225QF"), "--export",
                 str(tmp_path / "p.vrprofile.json")]) != 0
    assert "measure plan 'paper+apl'" in capsys.readouterr().err
    assert not (tmp_path / "p.vrprofile.json").exists()


def test_real_data_table_lists_both_sets_with_the_held_out_error():
    from workbench.diagnostics.real_data import real_data_table

    table = real_data_table(REAL, with_argyll=False)
    rows = {row.file: row for row in table.rows}
    for name in ("SamsungOLED_calib_2014-09-29.mat", "AW3225QF"):
        row = rows[name]
        assert not row.error and row.findings[0][0] == "apl-dependence", row
        assert row.apl_holdout and all(lum < lum0 for _, lum, _, lum0, _ in row.apl_holdout)
    assert "APL curve held out" in table.markdown()


def test_diagnose_json_on_a_session_without_a_display_model(capsys):
    import json

    from workbench.cli import main

    assert main(["diagnose", str(REAL / "SamsungOLED_calib_2014-09-29.mat"), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["baseline"] is None and document["extended"] is None
    assert [f["effect"] for f in document["findings"]] == ["apl-dependence"]
    assert {h["by"] for h in document["apl"]["holdout"]} == {"stabilizer level", "bias size"}
    assert len(document["untested"]) == 5


def test_a_truncated_samsung_file_is_refused_by_name_not_with_a_traceback(tmp_path):
    from workbench.errors import SpectrumFileError

    truncated = tmp_path / "SamsungOLED_truncated.mat"
    truncated.write_bytes((REAL / "SamsungOLED_calib_2014-09-29.mat").read_bytes()[:60000])
    with pytest.raises(SpectrumFileError, match="truncated or damaged"):
        read_session(truncated)
