"""The persistent user light-source library, two-peak metamers and measuring a light with the emulator."""

import numpy as np
import pytest

from workbench.errors import InputError, WorkbenchError
from workbench.illuminants import get_illuminant
from workbench.illuminants.comparison import colorchecker_comparison, source_row
from workbench.illuminants.light_measurement import (
    SimulatedLightBooth,
    measure_light_simulated,
)
from workbench.illuminants.metamers import two_peak_metamer
from workbench.illuminants.metrics import fidelity_Rf_Rg
from workbench.illuminants.user_library import (
    USER_LIBRARY_ENV,
    UserLibrary,
    resolve_illuminant,
    user_library_dir,
)
from workbench.profile import paper_vive_profile


def test_library_persists_between_instances_and_resolves_ids(tmp_path, monkeypatch):
    monkeypatch.setenv(USER_LIBRARY_ENV, str(tmp_path / "lib"))
    assert user_library_dir() == tmp_path / "lib"
    library = UserLibrary()
    assert library.ids() == []
    fl2 = get_illuminant("cie-fl2")
    first = library.add(fl2, name="Booth tube")
    second = library.add(fl2, name="Booth tube")
    assert (first, second) == ("user-booth-tube", "user-booth-tube-2")
    again = UserLibrary()
    assert again.ids() == [first, second]
    stored = resolve_illuminant(first)
    assert stored.name == "Booth tube" and stored.kind == "cie"
    np.testing.assert_allclose(stored.sd.values, fl2.sd.values, rtol=1e-7)
    again.remove(first)
    assert UserLibrary().ids() == [second]
    with pytest.raises(InputError, match="user-booth-tube"):
        again.get(first)


def test_a_corrupt_index_is_named(tmp_path):
    (tmp_path / "library.json").write_text("{not json")
    with pytest.raises(WorkbenchError, match="library.json"):
        UserLibrary(tmp_path).ids()


@pytest.mark.parametrize("source", ["cie-a", "cie-d50", "cie-fl2", "cie-fl11"])
def test_two_peak_metamer_has_the_sources_white_and_a_poor_rf(source):
    original = get_illuminant(source)
    metamer = two_peak_metamer(original)
    display = paper_vive_profile().display_model()
    a, b = source_row(original, display), source_row(metamer, display)
    assert abs(a.xy[0] - b.xy[0]) < 2e-6 and abs(a.xy[1] - b.xy[1]) < 2e-6
    assert a.rgb8_profile == b.rgb8_profile  # level 1 cannot tell them apart
    assert fidelity_Rf_Rg(metamer)[0] < 40
    comparison = colorchecker_comparison(metamer, display)
    assert comparison.level1_dE00.mean() > 3 * comparison.level2_dE00.mean()


def test_a_saturated_source_has_no_two_peak_metamer():
    import colour

    from workbench.colorimetry import WORKING_SHAPE
    from workbench.illuminants.source import Illuminant

    green = colour.sd_single_led(530, half_spectral_width=15, shape=WORKING_SHAPE)
    with pytest.raises(WorkbenchError, match="no two-peak"):
        two_peak_metamer(Illuminant("green", "green LED", "imported", green))


def test_measuring_a_simulated_booth_recovers_the_spectrum_and_illuminance():
    source = get_illuminant("cie-fl2")
    booth = SimulatedLightBooth(source, illuminance_lux=800.0)
    result = measure_light_simulated(booth, "FL2 booth", seed=3)
    assert result.Lv == pytest.approx(booth.luminance_cd_m2, rel=0.01)
    assert result.illuminant.kind == "measured"
    measured = result.illuminant.sd.values
    expected = source.sd.values / source.sd.values[180]  # 560 nm
    assert np.max(np.abs(measured - expected)) < 0.02 * expected.max()
    assert "CS-2000" in result.instrument


def test_booth_rejects_a_dark_booth():
    with pytest.raises(InputError, match="illuminance"):
        SimulatedLightBooth(get_illuminant("cie-a"), illuminance_lux=0)
