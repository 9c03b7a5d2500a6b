"""The paper's Tables 5 and 6 reproduced (acceptance of issue 5, items 5–7)."""

import pytest

from workbench.ishihara import Viewing, parse_observer, table5, table6, take_test
from workbench.ishihara.paper import PAPER_TABLE6_REFERENCE

REFERENCE = {r.qualification: r.answers for r in PAPER_TABLE6_REFERENCE}


@pytest.fixture(scope="module")
def result6():
    return table6()


@pytest.mark.parametrize("path", ["physical", "level-2"])
def test_paper_set_gives_the_reference_answers_and_classifies_under_d65(path, paper_plates,
                                                                        observers):
    for name, observer in observers.items():
        exam = take_test(paper_plates, observer, Viewing("cie-d65", path))
        assert exam.answers == REFERENCE[name], name
        assert exam.classification == name


def test_tritanope_passes_like_a_normal_observer(paper_plates):
    # Ishihara plates screen red-green deficiency only
    exam = take_test(paper_plates, parse_observer("tritan"), Viewing("cie-d65", "level-2"))
    assert exam.answers == REFERENCE["normal"] and exam.classification == "normal"


@pytest.mark.parametrize("deficiency", ["protan", "deutan"])
def test_mild_anomalous_trichromat_reads_more_plates_than_a_dichromat(deficiency, paper_plates):
    viewing = Viewing("cie-d65", "level-2")
    read = [take_test(paper_plates, parse_observer(f"{deficiency}:{s}"), viewing)
            .score.plates_read_normally for s in (0.2, 0.5, 0.8, 1.0)]
    assert read == sorted(read, reverse=True)
    assert read[0] > read[-1]
    assert take_test(paper_plates, parse_observer(f"{deficiency}:0.2"), viewing) \
        .classification == "normal"


def test_two_peak_source_level1_misleads_level2_does_not(result6):
    real = result6.finding("d65-two-peak", "physical")
    level1 = result6.finding("d65-two-peak", "level-1")
    level2 = result6.finding("d65-two-peak", "level-2")
    # the real plates under the two-peak lamp fail: normal observers read like protans
    assert "normal" in real.misclassified
    # level 2 shows exactly that; level 1 shows the D65 plates instead
    assert level2.faithful and not level2.changed_plates
    assert level1.misleads and set(level1.changed_plates["normal"]) >= {2, 3, 4, 5, 6, 7, 8, 9, 10}
    rows = {r.observer: r for r in result6.rows_for(level1.viewing)}
    assert rows["normal"].classification == "normal"
    assert rows["normal"].physical_classification != "normal"


def test_d65_level2_is_faithful(result6):
    assert result6.finding("cie-d65", "level-2").faithful
    assert all(r.matches_reference for r in result6.rows_for(Viewing("cie-d65", "level-2")))


def test_table5_end_to_end_through_the_cs2000_emulator():
    result = table5()
    assert [r.dot for r in result.rows] == [f"P{i}" for i in range(1, 11)]
    assert result.mean_dE00 <= 0.5
    assert result.plate3_mean_dE00 <= 0.5
    for row in result.rows:
        assert row.calculated[:2] == pytest.approx(row.paper_calculated[:2], abs=1e-4)
        assert row.calculated[2] == pytest.approx(row.paper_calculated[2], abs=0.05)
        assert row.measured[:2] == pytest.approx(row.calculated[:2], abs=0.005)
