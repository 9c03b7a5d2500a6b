"""Gamut outlines, polygon clipping and coverage figures, validation chromaticities."""

import numpy as np
import pytest

from workbench.display import SRGBDisplay
from workbench.errors import InputError
from workbench.gamut import (
    REFERENCE_GAMUTS,
    Gamut,
    clip_convex,
    display_gamut,
    gamut_coverage,
    polygon_area,
    reference_gamut,
    shipped_profile_gamuts,
    spectral_locus,
    validation_points,
)
from workbench.profile import paper_vive_profile


def test_clipping_two_squares_gives_their_overlap():
    a = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], dtype=float)
    b = a + 1.0
    assert polygon_area(clip_convex(a, b)) == pytest.approx(1.0)
    assert polygon_area(clip_convex(a, a[::-1])) == pytest.approx(4.0)
    assert polygon_area(clip_convex(a, a + 5.0)) == 0.0


def test_the_ideal_srgb_display_is_the_srgb_triangle_and_covers_all_of_it():
    gamut = display_gamut(SRGBDisplay())
    assert len(gamut.xy) == 3
    np.testing.assert_allclose(np.sort(gamut.xy, axis=0),
                               np.sort(reference_gamut("sRGB").xy, axis=0), atol=2e-4)
    for diagram in ("xy", "u'v'"):
        coverage = gamut_coverage(gamut, reference_gamut("sRGB"), diagram)
        assert coverage.covered_pct == pytest.approx(100.0, abs=0.05)
        assert coverage.relative_area_pct == pytest.approx(100.0, abs=0.05)


def test_srgb_covers_about_three_quarters_of_p3_and_half_of_rec2020_in_xy():
    srgb = reference_gamut("sRGB")
    p3 = gamut_coverage(srgb, reference_gamut("DCI-P3"), "xy")
    rec2020 = gamut_coverage(srgb, reference_gamut("Rec. 2020"), "xy")
    # The textbook figures: sRGB is ~74 % of P3 and ~53 % of Rec. 2020 by xy area.
    assert p3.covered_pct == pytest.approx(73.7, abs=0.5)
    assert rec2020.covered_pct == pytest.approx(52.9, abs=0.5)


def test_the_papers_vive_gamut_is_wider_than_srgb():
    vive = display_gamut(paper_vive_profile().display_model(), "vive")
    coverage = gamut_coverage(vive, reference_gamut("sRGB"))
    assert coverage.covered_pct > 99 and coverage.relative_area_pct > 130
    wide = gamut_coverage(vive, reference_gamut("Rec. 2020"))
    assert wide.covered_pct == pytest.approx(wide.relative_area_pct, abs=0.5)  # inside Rec. 2020


def test_locus_and_unknown_names():
    wavelengths, xy = spectral_locus("xy")
    assert xy[np.argmin(np.abs(wavelengths - 520))][1] > 0.8
    with pytest.raises(InputError, match="diagram"):
        spectral_locus("Lab")
    with pytest.raises(InputError, match="reference gamut"):
        reference_gamut("Adobe")
    assert set(REFERENCE_GAMUTS) == {"sRGB", "DCI-P3", "Rec. 2020"}
    assert isinstance(reference_gamut("sRGB"), Gamut)


def test_validation_points_from_a_diagnosis():
    from workbench.diagnostics import diagnose
    from workbench.simulated_sessions import simulate_session

    session = simulate_session({"channel-interaction": 0.1}, seed=2, plan="quick")
    diagnosis = diagnose(session)
    points = validation_points(diagnosis)
    assert len(points) == int(session.mask("validation").sum())
    assert np.max(np.abs(points.measured_xy - points.predicted_xy)) < 0.02
    assert validation_points(None, None, None) is None


def test_shipped_profiles_include_the_papers_vive():
    names = [g.name for _, g in shipped_profile_gamuts()]
    assert any("Vive" in name for name in names)
