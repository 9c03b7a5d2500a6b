"""Inputs that cannot be right are refused by name, with the fix (issue 11, point 8)."""

import re

import numpy as np
import pytest

from workbench.errors import SpectrumFileError
from workbench.session import read_session_csv, write_session_csv
from workbench.session_readers import read_session
from workbench.simulated_sessions import simulate_session


@pytest.fixture(scope="module")
def session_rows(tmp_path_factory):
    path = tmp_path_factory.mktemp("inputs") / "session.csv"
    write_session_csv(simulate_session(None, seed=2), path)
    return path.read_text().splitlines()


def _write(tmp_path, lines):
    path = tmp_path / "edited.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def _ramp_line(lines) -> int:
    return next(i for i, line in enumerate(lines) if line.startswith("ramp-r,"))


def test_a_negative_luminance_on_a_ramp_row_is_refused_with_its_line(tmp_path, session_rows):
    lines = list(session_rows)
    i = _ramp_line(lines)
    cells = lines[i].split(",")
    cells[5] = "-50"  # Y
    lines[i] = ",".join(cells)
    with pytest.raises(SpectrumFileError, match=rf"line {i + 1}: .*negative beyond noise"):
        read_session_csv(_write(tmp_path, lines))


def test_a_slightly_negative_black_from_a_dark_subtracting_instrument_is_read(tmp_path,
                                                                               session_rows):
    lines = list(session_rows)
    i = next(i for i, line in enumerate(lines) if line.startswith("black,"))
    cells = lines[i].split(",")
    cells[4:7] = ["-0.001", "-0.002", "-0.001"]
    lines[i] = ",".join(cells)
    session = read_session_csv(_write(tmp_path, lines))
    assert session.XYZ[i - 1, 1] == -0.002


def test_fractional_dac_values_are_refused(tmp_path, session_rows):
    lines = list(session_rows)
    i = _ramp_line(lines)
    cells = lines[i].split(",")
    cells[1] = "12.5"
    lines[i] = ",".join(cells)
    with pytest.raises(SpectrumFileError, match=r"not whole numbers.*read from the \.ti3"):
        read_session_csv(_write(tmp_path, lines))


def test_a_ti3_whose_number_of_sets_disagrees_with_its_rows_is_refused(tmp_path):
    from workbench.measurement.ti3 import write_session_ti3

    path = write_session_ti3(simulate_session(None, seed=2), tmp_path / "session.ti3")
    text = path.read_text()
    count = int(re.search(r"NUMBER_OF_SETS\s+(\d+)", text).group(1))
    edited = tmp_path / "edited.ti3"
    edited.write_text(text.replace(f"NUMBER_OF_SETS {count}", f"NUMBER_OF_SETS {count + 3}", 1))
    with pytest.raises(SpectrumFileError, match=rf"NUMBER_OF_SETS says {count + 3} rows but the "
                                                rf"first data table holds {count}"):
        read_session(edited)
    assert len(read_session(path)) == count


@pytest.mark.parametrize("white", ["abc", "95.1 100.0"])
def test_a_ti3_whose_absolute_white_is_not_three_numbers_is_refused(tmp_path, white):
    from workbench.measurement.ti3 import write_session_ti3

    path = write_session_ti3(simulate_session(None, seed=2), tmp_path / "session.ti3")
    edited = tmp_path / "edited.ti3"
    edited.write_text(re.sub(r'LUMINANCE_XYZ_CDM2 "[^"]*"', f'LUMINANCE_XYZ_CDM2 "{white}"', path.read_text()))
    with pytest.raises(SpectrumFileError, match="LUMINANCE_XYZ_CDM2 .* is not three numbers"):
        read_session(edited)


def test_noise_model_is_not_fooled_by_heavy_tails_or_a_wandering_display():
    """Student-t noise is estimated without the bias of a plain median; a display that wanders
    over minutes inflates the whole scatter, not the repeatability (points measured in turn)."""
    from tests.diagnostics.independent_generator import generate_session
    from workbench.diagnostics.noise import estimate_noise

    ratios = []
    for seed in range(12):
        generated = generate_session({}, seed=seed)
        model = estimate_noise(generated.session.without("validation"))
        ratios.append(model.relative_sd_at(1.0) / (generated.noise * np.sqrt(1.1)))
    assert 0.85 < np.median(ratios) < 1.2
    wandering = generate_session({"temporal-drift": "wander"}, seed=7, noise=0.001)
    model = estimate_noise(wandering.session.without("validation"))
    assert model.relative_sd_at(1.0) < 0.0015
    assert model.dof > 10 and model.source == "sweep scatter"


def test_a_sweep_no_power_law_fits_is_a_shape_even_when_no_alternative_bends_to_it():
    from workbench.diagnostics.detectors import LACK_OF_FIT, _tone_test_points

    drive = np.concatenate([[0.0], np.arange(5, 256, 5) / 255])
    power = drive ** 2.2
    s_curve = 0.65 * power + 0.35 * (3 * power ** 2 - 2 * power ** 3)
    rng = np.random.default_rng(1)
    for truth, shaped in ((s_curve, True), (power, False)):
        Y = 100 * truth * (1 + 0.002 * rng.standard_normal(drive.size)) + 0.01
        sd = np.hypot(0.002 * 100 * truth, 0.01)
        p, gap, standard_error, form, z = _tone_test_points(drive, Y, sd, 0.0, 100.0, 35.0)
        if shaped:
            # GOG, extended power and two harmonics all fail on the dark points: lack of fit
            assert form == LACK_OF_FIT and p < 1e-6 and gap > 0.01
        else:
            assert p > 0.05
