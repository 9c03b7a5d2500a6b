import numpy as np
import pytest

from workbench.colorimetry import observer_cmfs
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


def test_machado_dichromat_has_l_proportional_to_m():
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


def _outside_span(vectors, basis):
    """Relative residual of each column of ``vectors`` outside the span of ``basis``'s columns."""
    coefficients, *_ = np.linalg.lstsq(basis, vectors, rcond=None)
    return np.linalg.norm(basis @ coefficients - vectors, axis=0) / np.linalg.norm(vectors, axis=0)


def test_machado_anomalous_cones_are_blends_so_linear_in_cie1931():
    cmfs = observer_cmfs("cie1931-2").values
    for name in ("protan:0.5", "deutan:0.3", "protan"):
        assert _outside_span(parse_observer(name).fundamentals, cmfs).max() < 1e-3, name
    for name in ("normal@ss2000", "protan:0.5@ss2000", "deutan:0.3@ss2000"):
        assert _outside_span(parse_observer(name).fundamentals[:, :2], cmfs).min() > 0.01, name


def test_stockman_sharpe_observers_parse_and_describe_themselves():
    observer = parse_observer("Deutan:0.5@SS2000")
    assert observer.name == "deutan:0.5@ss2000" and observer.fundamentals_id == "ss2000"
    assert "M pigment shifted" in observer.description and "Stockman & Sharpe" in observer.description
    assert parse_observer("normal@ss2000").description.startswith("normal trichromat (Stockman")
    assert simulated_observer("protan", 0.5).description.startswith(
        "protanomalous trichromat (severity 0.5, L blended towards M")
    protanope = parse_observer("protan@ss2000")
    np.testing.assert_array_equal(protanope.fundamentals[:, 0], protanope.fundamentals[:, 1])
    with pytest.raises(InputError, match="ss2000"):
        parse_observer("normal@cie2006")
    with pytest.raises(InputError, match="after '@'"):
        parse_observer("normal@")


def test_stockman_sharpe_discrimination_falls_with_severity():
    ochre, green = _radiance("ochre"), _radiance("green-p")
    differences = [float(parse_observer(f"protan:{s}@ss2000").colour_difference(ochre, green))
                   for s in (0.1, 0.3, 0.5, 0.7, 0.9, 1.0)]
    assert all(a > b for a, b in zip(differences, differences[1:]))
    assert float(parse_observer("normal@ss2000").colour_difference(ochre, green)) > differences[0]
