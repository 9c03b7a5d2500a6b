import numpy as np
import pytest

from workbench.errors import InputError
from workbench.ishihara.observers import parse_observer
from colour import XYZ_to_xyY, xyY_to_XYZ

from workbench.ishihara.palette import (
    D65_reflectance_XYZ,
    XYZ_to_reflectance,
    design_palette,
    paper_dot_colours,
)
from workbench.ishihara.cones import confusion_line_residual
from workbench.ishihara.paper import PAPER_TABLE5
from workbench.ishihara.reading import LEGIBILITY_THRESHOLD_JND
from workbench.illuminants import get_illuminant


@pytest.fixture(scope="module")
def palette():
    return design_palette()


def test_reflectances_lie_in_0_1_and_reach_their_design_targets(palette):
    for colour in palette:
        assert colour.reflectance.shape == (401,)
        assert colour.reflectance.min() >= 0.0 and colour.reflectance.max() <= 1.0, colour.name
        xyY = XYZ_to_xyY(D65_reflectance_XYZ(colour.reflectance))
        np.testing.assert_allclose(xyY, colour.xyY, atol=1e-9, err_msg=colour.name)


def test_paper_dots_have_table5_calculated_chromaticity_and_luminance():
    dots = paper_dot_colours()
    assert [d.name for d in dots] == [f"P{i}" for i in range(1, 11)]
    for dot, paper in zip(dots, PAPER_TABLE5):
        xyY = XYZ_to_xyY(D65_reflectance_XYZ(dot.reflectance)) * [1, 1, 100]
        np.testing.assert_allclose(xyY, paper.calculated_xyY, atol=1e-8)


def _partner_pairs(palette):
    return [(c.name, partner, deficiency) for c in palette for deficiency, partner in c.partners]


def test_partners_lie_on_the_intended_confusion_lines(palette):
    pairs = _partner_pairs(palette)
    assert {d for _, _, d in pairs} == {"protan", "deutan", "tritan"}
    for a, b, deficiency in pairs:
        residual = confusion_line_residual(palette[a].xyY[:2], palette[b].xyY[:2], deficiency)
        assert residual < 1e-9, (a, b, deficiency)


def test_red_green_partners_are_metamers_for_the_dichromat_but_not_for_normal(palette):
    d65 = get_illuminant("cie-d65").sd.values
    normal = parse_observer("normal")
    for a, b, deficiency in _partner_pairs(palette):
        if deficiency == "tritan":
            continue
        radiance_a, radiance_b = palette[a].reflectance * d65, palette[b].reflectance * d65
        dichromat = parse_observer(deficiency)
        assert dichromat.colour_difference(radiance_a, radiance_b) < 1e-6, (a, b)
        assert normal.colour_difference(radiance_a, radiance_b) > 2 * LEGIBILITY_THRESHOLD_JND, (a, b)


def test_lightness_jitter_is_the_papers_darkest_to_lightest_ratio(palette):
    ratios = [min(d.calculated_xyY[2] for d in PAPER_TABLE5 if d.family == f)
              / max(d.calculated_xyY[2] for d in PAPER_TABLE5 if d.family == f)
              for f in ("green", "ochre", "purple", "bluish-green")]
    assert palette.lightness_range == pytest.approx((min(ratios), 1.0))


def test_unknown_colour_method_and_impossible_colour_are_named(palette):
    with pytest.raises(InputError, match="Otsu 2018"):
        XYZ_to_reflectance([0.2, 0.2, 0.2], method="Jakob 2019")
    with pytest.raises(InputError, match="object-colour solid"):
        XYZ_to_reflectance(xyY_to_XYZ([0.60, 0.30, 0.60]))
    with pytest.raises(InputError, match="ochre"):
        palette["vermilion"]
