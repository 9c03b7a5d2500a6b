import numpy as np
import pytest

from workbench.errors import InputError
from workbench.ishihara.observers import parse_observer, simulated_observer
from workbench.ishihara.palette import design_palette
from workbench.illuminants import get_illuminant


def _radiance(name):
    return design_palette()[name].reflectance * get_illuminant("cie-d65").sd.values


def test_parse_observer_names_and_descriptions():
    assert parse_observer("normal").description == "normal trichromat"
    assert parse_observer("Protan").name == "protan"
    assert parse_observer("deutan:0.5").description.startswith("deuteranomalous trichromat")
    assert parse_observer("tritan").dimensions == 1
    assert parse_observer("protan").dimensions == 2


@pytest.mark.parametrize("text, match", [
    ("protan:1.5", r"\(0, 1\]"), ("deutan:0", r"\(0, 1\]"), ("protan:abc", "not a number"),
    ("normal:0.5", "no severity"), ("tritan:0.5", "tritanope"), ("monochromat", "deutan"),
])
def test_bad_observers_are_named_with_the_fix(text, match):
    with pytest.raises(InputError, match=match):
        parse_observer(text)


def test_dichromat_is_machado_shift_of_20nm_with_l_proportional_to_m():
    protanope = simulated_observer("protan", 1.0)
    L, M = protanope.fundamentals[:, 0], protanope.fundamentals[:, 1]
    ratio = L[M > 1e-3] / M[M > 1e-3]
    assert np.ptp(ratio) < 1e-9 * ratio.mean()


def test_discrimination_of_a_protan_confusion_pair_falls_with_severity():
    ochre, green = _radiance("ochre"), _radiance("green-p")
    differences = [float(parse_observer(f"protan:{s}").colour_difference(ochre, green))
                   for s in (0.1, 0.3, 0.5, 0.7, 0.9)]
    assert all(a > b for a, b in zip(differences, differences[1:]))
    assert float(parse_observer("normal").colour_difference(ochre, green)) > differences[0]
    assert float(parse_observer("protan").colour_difference(ochre, green)) < 1e-6


def test_chromatic_coordinates_ignore_intensity_and_reject_bad_radiance():
    observer = parse_observer("normal")
    radiance = _radiance("purple")
    np.testing.assert_allclose(observer.chromatic_coordinates(3.7 * radiance),
                               observer.chromatic_coordinates(radiance), atol=1e-9)
    with pytest.raises(InputError, match="401"):
        observer.chromatic_coordinates(radiance[:100])
    bad = radiance.copy()
    bad[10] = np.nan
    with pytest.raises(InputError, match="NaN"):
        observer.chromatic_coordinates(bad)
    with pytest.raises(InputError, match="no chromaticity"):
        observer.chromatic_coordinates(np.zeros(401))
