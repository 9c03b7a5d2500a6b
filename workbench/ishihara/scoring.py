"""Scoring a set of answers by Ishihara's rules, to a classification.

Ishihara's instructions (38-plate edition) judge colour vision on the
screening plates 1–21: read normally 17 or more → normal; 13 or fewer →
deficient; in between the result is not conclusive. Plate 1 (the
demonstration) is read by everyone, so a subject who misreads it has not taken
the test properly. The classification plates then tell protan from deutan:
protans read only the digit that the protan-confusion colours do not hide,
deutans only the other.

A reduced set (the paper's ten plates) keeps the same *proportions*: its
screening plates are every plate but the classification ones, and the two
thresholds are 17/21 and 13/21 of their number.

References
----------
Ishihara, S. *Ishihara's Tests for Colour Deficiency*, 38 Plates Edition,
Kanehara Trading: "Analysis of the results".
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from workbench.errors import InputError

__all__ = [
    "ISHIHARA38_SCREENING_PLATES",
    "ISHIHARA38_NORMAL_AT_LEAST",
    "ISHIHARA38_DEFICIENT_AT_MOST",
    "CLASSIFICATIONS",
    "IshiharaScore",
    "score_answers",
]

ISHIHARA38_SCREENING_PLATES = 21
ISHIHARA38_NORMAL_AT_LEAST = 17
ISHIHARA38_DEFICIENT_AT_MOST = 13

CLASSIFICATIONS = ("normal", "protan", "deutan", "red-green deficient (type undetermined)",
                   "inconclusive", "invalid")
"""Every verdict :func:`score_answers` can give."""


@dataclass(frozen=True)
class IshiharaScore:
    """The outcome of one test.

    Attributes
    ----------
    answers : tuple of str
        One per plate.
    read_normally : tuple of bool
        Whether each plate was read as a normal observer reads it.
    screening_read_normally : int
        Screening plates read normally.
    screening_plates : int
        Number of screening plates.
    normal_at_least, deficient_at_most : int
        The thresholds applied (Ishihara's proportions on this set).
    classification : str
        One of :data:`CLASSIFICATIONS`.
    """

    answers: tuple
    read_normally: tuple
    screening_read_normally: int
    screening_plates: int
    normal_at_least: int
    deficient_at_most: int
    classification: str

    @property
    def plates_read_normally(self) -> int:
        """All plates (screening and classification) read as a normal observer reads them."""
        return int(sum(self.read_normally))


def score_answers(specs, answers) -> IshiharaScore:
    """Score ``answers`` to the plates ``specs`` (:class:`~workbench.ishihara.plates.PlateSpec`).

    Parameters
    ----------
    specs : sequence of PlateSpec
        The plates, with their expected answers.
    answers : sequence of str
        What the subject read, one per plate (``"-"`` for nothing).

    Returns
    -------
    IshiharaScore
    """
    specs, answers = tuple(specs), tuple(str(a) for a in answers)
    if len(specs) != len(answers):
        raise InputError(f"{len(answers)} answers for {len(specs)} plates; give one answer per "
                         "plate ('-' where nothing was read)")
    read_normally = tuple(a == s.normal for s, a in zip(specs, answers))
    screening = [i for i, s in enumerate(specs) if s.kind != "classification"]
    if not screening:
        raise InputError("the plate set has no screening plate; it cannot be scored")
    count = len(screening)
    normal_at_least = int(np.ceil(count * ISHIHARA38_NORMAL_AT_LEAST / ISHIHARA38_SCREENING_PLATES))
    deficient_at_most = int(np.floor(count * ISHIHARA38_DEFICIENT_AT_MOST
                                     / ISHIHARA38_SCREENING_PLATES))
    passed = sum(read_normally[i] for i in screening)
    demonstrations = [i for i, s in enumerate(specs) if s.kind == "demonstration"]
    if any(not read_normally[i] for i in demonstrations):
        verdict = "invalid"
    elif passed >= normal_at_least:
        verdict = "normal"
    elif passed <= deficient_at_most:
        verdict = _deficiency_type(specs, answers)
    else:
        verdict = "inconclusive"
    return IshiharaScore(answers=answers, read_normally=read_normally,
                         screening_read_normally=int(passed), screening_plates=count,
                         normal_at_least=normal_at_least, deficient_at_most=deficient_at_most,
                         classification=verdict)


def _deficiency_type(specs, answers) -> str:
    votes = Counter()
    for spec, answer in zip(specs, answers):
        if spec.kind != "classification":
            continue
        if answer == spec.protan:
            votes["protan"] += 1
        elif answer == spec.deutan:
            votes["deutan"] += 1
    if votes and (len(votes) == 1 or votes["protan"] != votes["deutan"]):
        return votes.most_common(1)[0][0]
    return "red-green deficient (type undetermined)"
