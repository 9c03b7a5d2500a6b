import numpy as np
import pytest

from workbench.ishihara.cones import (
    LMS_to_XYZ,
    XYZ_to_LMS,
    cone_fundamentals_Smith_Pokorny1975,
    confusion_line_residual,
    copunctal_point,
)
from workbench.colorimetry import observer_cmfs


@pytest.mark.parametrize("deficiency, published", [
    ("protan", (0.7465, 0.2535)),   # Wyszecki & Stiles (1982); Viénot et al. (1999)
    ("deutan", (1.40, -0.40)),
    ("tritan", (0.1748, 0.0)),
])
def test_copunctal_points_are_the_published_ones(deficiency, published):
    assert copunctal_point(deficiency) == pytest.approx(published, abs=5e-4)


def test_unknown_deficiency_names_the_valid_ones():
    with pytest.raises(ValueError, match="deutan"):
        copunctal_point("achromat")


def test_fundamentals_are_linear_in_cie1931_and_l_plus_m_is_y():
    fundamentals = cone_fundamentals_Smith_Pokorny1975()
    cmfs = observer_cmfs().values
    assert fundamentals.shape == (401, 3)
    np.testing.assert_allclose(fundamentals[:, 0] + fundamentals[:, 1], cmfs[:, 1], atol=1e-4)
    XYZ = np.array([[0.2, 0.3, 0.4], [50.0, 40.0, 10.0]])
    np.testing.assert_allclose(LMS_to_XYZ(XYZ_to_LMS(XYZ)), XYZ, atol=1e-12)


def test_confusion_line_residual_is_zero_along_a_line_and_not_across():
    point = copunctal_point("protan")
    a = np.array([0.35, 0.38])
    on_line = point + 0.5 * (a - point)
    assert confusion_line_residual(a, on_line, "protan") == pytest.approx(0, abs=1e-12)
    assert confusion_line_residual(a, [0.35, 0.36], "protan") > 1e-3
