"""A simulated observer takes the test: reads each plate as shown, and is scored.

:func:`read_plate` chains the pieces for one plate — what reaches the eye from
each dot (:mod:`~workbench.ishihara.viewing`), the observer's colours of the
dots (:mod:`~workbench.ishihara.observers`) and the reading model
(:mod:`~workbench.ishihara.reading`); :func:`take_test` does it for a set and
scores the answers by Ishihara's rules (:mod:`~workbench.ishihara.scoring`).
"""

from __future__ import annotations

from dataclasses import dataclass

from workbench.ishihara.hmd import CalibratedHeadset
from workbench.ishihara.observers import Observer
from workbench.ishihara.plates import Plate
from workbench.ishihara.reading import Reading, read_dots
from workbench.ishihara.scoring import IshiharaScore, score_answers
from workbench.ishihara.viewing import Viewing, dot_radiance

__all__ = ["Examination", "read_plate", "take_test"]


@dataclass(frozen=True)
class Examination:
    """One observer's test under one viewing condition.

    Attributes
    ----------
    observer : str
        The observer's name (``"normal"``, ``"protan:0.5"`` …).
    viewing : Viewing
    readings : tuple of Reading
        One per plate.
    score : IshiharaScore
    """

    observer: str
    viewing: Viewing
    readings: tuple
    score: IshiharaScore

    @property
    def answers(self) -> tuple:
        return self.score.answers

    @property
    def classification(self) -> str:
        return self.score.classification


def read_plate(plate: Plate, observer: Observer, viewing: Viewing = Viewing(),
               hmd: CalibratedHeadset | None = None) -> Reading:
    """What ``observer`` reads on ``plate`` seen as ``viewing`` says (default: HMD, level 2, D65)."""
    radiance = dot_radiance(plate.dot_reflectances, viewing, hmd)
    return read_dots(plate.layout, observer.chromatic_coordinates(radiance))


def take_test(plates, observer: Observer, viewing: Viewing = Viewing(),
              hmd: CalibratedHeadset | None = None) -> Examination:
    """``observer`` reads every plate of ``plates``; the answers scored by Ishihara's rules."""
    plates = tuple(plates)
    readings = tuple(read_plate(p, observer, viewing, hmd) for p in plates)
    score = score_answers([p.spec for p in plates], [r.answer for r in readings])
    return Examination(observer=observer.name, viewing=viewing, readings=readings, score=score)
