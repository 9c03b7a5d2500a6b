import colour
import numpy as np
import pytest
from scipy.signal import find_peaks

from workbench.errors import InputError, SpectrumFileError
from workbench.illuminants import (
    get_illuminant,
    illuminant_metrics,
    list_illuminants,
    read_illuminant_file,
    write_illuminant_file,
)
from workbench.illuminants.synthesized import SIMULATOR_CHANNELS, d65_simulator_channel_powers


def test_builtin_ids_are_stable():
    ids = set(list_illuminants())
    expected = {"cie-a", "cie-d50", "cie-d65", "cie-led-b1", "cie-fl3-15", "d65-two-peak",
                "d65-simulator"} | {f"cie-fl{i}" for i in range(1, 13)}
    assert expected <= ids
    assert get_illuminant("CIE-D65").id == "cie-d65"


def test_unknown_id_suggests_close_ones():
    with pytest.raises(InputError, match="did you mean .*cie-d65"):
        get_illuminant("cie-d56")


def test_d65_acceptance_figures():
    m = illuminant_metrics(get_illuminant("cie-d65"))
    np.testing.assert_allclose(m.XYZ, [80.81, 85.00, 92.57], atol=0.1)
    assert m.rgb8_srgb == (237, 237, 237)
    assert m.CCT == pytest.approx(6504, abs=3)
    assert m.Rf == pytest.approx(100, abs=0.05)
    assert m.level1_mean_dE00 < 1.0


def test_d50_light_colour():
    assert illuminant_metrics(get_illuminant("cie-d50")).rgb8_srgb == (255, 235, 205)


def test_cct_and_duv_of_illuminant_a():
    m = illuminant_metrics(get_illuminant("cie-a"))
    assert m.CCT == pytest.approx(2856, abs=2)
    assert abs(m.Duv) < 5e-4


def test_two_peak_source_is_a_d65_metamer_with_very_low_fidelity():
    source = get_illuminant("d65-two-peak")
    m = illuminant_metrics(source)
    d65 = illuminant_metrics(get_illuminant("cie-d65"))
    assert np.hypot(*(np.array(m.xy) - d65.xy)) < 1e-4
    assert m.Rf < 10
    # exactly two emission peaks, one blue and one yellow
    peaks, _ = find_peaks(source.values, prominence=0.05 * source.values.max())
    assert len(peaks) == 2
    blue, yellow = source.wavelengths[peaks]
    assert 430 <= blue <= 480 and 555 <= yellow <= 600
    assert m.level1_mean_dE00 > 5  # level 1 is not enough under it


def test_d65_simulator_has_at_least_five_peaks_and_good_fidelity():
    m = illuminant_metrics(get_illuminant("d65-simulator"))
    d65 = illuminant_metrics(get_illuminant("cie-d65"))
    powers = d65_simulator_channel_powers()
    assert len(SIMULATOR_CHANNELS) >= 5
    assert np.sum(powers > 0.02 * powers.max()) >= 5  # at least five LEDs really contribute
    assert np.hypot(*(np.array(m.xy) - d65.xy)) < 0.005
    assert m.Rf >= 85


def test_metrics_for_a_profile_display():
    from profiles import example_profile_path
    from workbench.profile import load_profile

    display = load_profile(example_profile_path("htc-vive-paper")).display_model()
    m = illuminant_metrics(get_illuminant("cie-d65"), display)
    assert m.rgb8_display != m.rgb8_srgb
    assert m.light_in_gamut


@pytest.mark.parametrize("suffix", [".csv", ".xml"])
def test_file_round_trip(tmp_path, suffix):
    source = get_illuminant("cie-fl11")
    path = write_illuminant_file(source, tmp_path / f"fl11{suffix}")
    again = read_illuminant_file(path)
    np.testing.assert_allclose(again.values, source.values, rtol=1e-6)
    assert again.kind == "imported"
    assert get_illuminant(str(path)).id == f"file:{path}"


BAD_CSV = {
    "text": ("wavelength,value\n400,1\n410,abc\n", r"line 3: '410','abc' is not numeric"),
    "negative": ("400,1\n500,-0.5\n700,1\n", r"line 2: negative power -0.5 at 500 nm"),
    "unsorted": ("400,1\n500,1\n450,1\n700,1\n", r"line 3: wavelength 450 nm comes after 500"),
    "duplicate": ("400,1\n500,1\n500,2\n700,1\n", r"line 3: wavelength 500 nm appears twice"),
    "narrow": ("450,1\n500,1\n600,1\n", r"covers 450–600 nm, too narrow"),
    "nan": ("400,1\n500,nan\n700,1\n", r"line 2: the value at 500 nm is nan"),
    "empty": ("wavelength,value\n", r"no data rows"),
}


@pytest.mark.parametrize("case", sorted(BAD_CSV))
def test_bad_csv_files_name_file_line_and_fix(tmp_path, case):
    text, message = BAD_CSV[case]
    path = tmp_path / f"{case}.csv"
    path.write_text(text)
    with pytest.raises(SpectrumFileError, match=message) as info:
        read_illuminant_file(path)
    assert str(path) in str(info.value) and "Fix:" in str(info.value)


def test_bad_xml_and_unknown_suffix(tmp_path):
    path = tmp_path / "broken.xml"
    path.write_text("<IESTM2714><Header>")
    with pytest.raises(SpectrumFileError, match="broken.xml"):
        read_illuminant_file(path)
    with pytest.raises(SpectrumFileError, match="unknown spectrum file type"):
        read_illuminant_file(tmp_path / "x.txt")


def test_imported_narrow_but_valid_range_is_extended(tmp_path):
    path = tmp_path / "led.csv"
    rows = "\n".join(f"{w},{np.exp(-((w - 550) / 40) ** 2):.6f}" for w in range(400, 701, 5))
    path.write_text(rows + "\n")
    source = read_illuminant_file(path)
    assert source.values.shape == (401,)
    assert "end values held" in source.description
