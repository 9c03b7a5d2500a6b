import pytest

from workbench.errors import InputError
from workbench.ishihara.paper import PAPER_TABLE6_OBSERVERS, PAPER_TABLE6_REFERENCE
from workbench.ishihara.plates import paper_plate_set_specs
from workbench.ishihara.scoring import score_answers


@pytest.fixture(scope="module")
def specs():
    return paper_plate_set_specs()


def test_reference_answers_classify_as_their_qualification(specs):
    for row in PAPER_TABLE6_REFERENCE:
        assert score_answers(specs, row.answers).classification == row.qualification


def test_thresholds_are_ishiharas_proportions(specs):
    score = score_answers(specs, PAPER_TABLE6_REFERENCE[0].answers)
    assert score.screening_plates == 9
    assert (score.normal_at_least, score.deficient_at_most) == (8, 5)   # ⌈9·17/21⌉, ⌊9·13/21⌋


def test_misread_demonstration_invalidates_and_middle_counts_are_inconclusive(specs):
    normal = list(PAPER_TABLE6_REFERENCE[0].answers)
    assert score_answers(specs, ["-"] + normal[1:]).classification == "invalid"
    one_wrong = normal[:1] + ["3"] + normal[2:]
    assert score_answers(specs, one_wrong).classification == "normal"            # 8 of 9
    three_wrong = normal[:1] + ["3", "5", "2"] + normal[4:]
    assert score_answers(specs, three_wrong).classification == "inconclusive"    # 6 of 9
    four_wrong = normal[:1] + ["3", "5", "2", "5"] + normal[5:]
    assert score_answers(specs, four_wrong).classification \
        == "red-green deficient (type undetermined)"                               # 5 of 9


def test_deficient_without_a_classification_answer_is_type_undetermined(specs):
    protan = list(PAPER_TABLE6_REFERENCE[1].answers)
    assert score_answers(specs, protan[:-1] + ["26"]).classification \
        == "red-green deficient (type undetermined)"


def test_the_papers_real_deficient_observers_classify_as_qualified(specs):
    for row in PAPER_TABLE6_OBSERVERS:
        if row.qualification != "normal":
            assert score_answers(specs, row.answers).classification == row.qualification, row.observer


def test_wrong_number_of_answers_is_refused(specs):
    with pytest.raises(InputError, match="one answer per plate"):
        score_answers(specs, ["12"])
