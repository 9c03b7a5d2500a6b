"""How a simulated observer reads a plate: figure–ground split, then glyph matching.

1. **Colour of each dot.** The observer maps each dot's spectral radiance to
   its chromatic coordinates (:meth:`Observer.chromatic_coordinates`, in JND of
   the receptor-noise model; lightness plays no part).
2. **Figure–ground split.** The observer groups the dots by colour into the
   two groups that differ most: a two-means clustering weighted by dot area,
   started from the best threshold (Otsu's criterion) along the principal
   axis of the dots' colours. This is the *dominant* grouping: a weaker
   difference is masked by a stronger one, which is how transformation and
   hidden-digit plates work (a normal observer groups by the red–green
   difference and misses a figure drawn in a weaker blue–yellow difference; a
   red–green deficient observer, who lacks the red–green difference, sees it).
3. **Legibility.** If the two groups' mean colours are less than
   :data:`LEGIBILITY_THRESHOLD_JND` apart, the plate looks uniform: ``"-"``.
4. **Digit.** Each group's dots are compared with every glyph the plates can
   show (one digit centred, one digit in the left or right slot of a pair, or a
   pair) by intersection over union of dot areas; the best match is read if
   it reaches :data:`GLYPH_MATCH_THRESHOLD`, otherwise ``"-"`` (colours differ
   but they draw no digit: the camouflage of a vanishing plate).

Scale: colour differences in JND of the observer's space; matches on 0..1.

References
----------
Ishihara, S. *Ishihara's Tests for Colour Deficiency*, 38 Plates Edition,
instructions (plate types: transformation, vanishing, hidden digit).

Otsu, N. (1979). A threshold selection method from gray-level histograms.
*IEEE Transactions on Systems, Man, and Cybernetics*, 9(1), 62–66.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from workbench.errors import InputError
from workbench.ishihara.glyphs import LAYOUT_SLOTS, text_mask
from workbench.ishihara.packing import DotLayout

__all__ = [
    "LEGIBILITY_THRESHOLD_JND",
    "GLYPH_MATCH_THRESHOLD",
    "DOT_IN_GLYPH_FRACTION",
    "NOTHING_READ",
    "Reading",
    "candidate_texts",
    "dots_in_mask",
    "split_in_two",
    "read_dots",
]

LEGIBILITY_THRESHOLD_JND = 5.0
"""Least colour difference (JND) between figure and ground for a figure to be read.

Ishihara figures are read at a glance, in crowded dots of random lightness:
a clearly suprathreshold difference, five just-noticeable differences.
"""

GLYPH_MATCH_THRESHOLD = 0.6
"""Least intersection over union (dot areas) between a group and a glyph to read it."""

DOT_IN_GLYPH_FRACTION = 0.5
"""A dot belongs to a glyph when at least this fraction of its pixels does."""

NOTHING_READ = "-"

_MAX_ITERATIONS = 50


@dataclass(frozen=True)
class Reading:
    """What an observer reads on one plate.

    Attributes
    ----------
    answer : str
        The digits read, or ``"-"``.
    contrast_jnd : float
        Colour difference between the two groups the observer sees (JND).
    match : float
        Intersection over union of the best glyph (0..1).
    best_guess : str
        That glyph's digits, even when not legible.
    reason : str
        ``"read"``, ``"no colour contrast"`` or ``"no digit shape"``.
    """

    answer: str
    contrast_jnd: float
    match: float
    best_guess: str
    reason: str


def candidate_texts() -> tuple:
    """Every ``(answer, text, slot)`` a plate can show: single digits in each slot, pairs 10–99."""
    singles = [(d, d, slot) for slot in LAYOUT_SLOTS for d in "0123456789"]
    pairs = [(f"{a}{b}", f"{a}{b}", None) for a in "123456789" for b in "0123456789"]
    return tuple(singles + pairs)


def dots_in_mask(layout: DotLayout, mask: np.ndarray) -> np.ndarray:
    """Which dots (N,) lie in ``mask`` (at least :data:`DOT_IN_GLYPH_FRACTION` of their pixels)."""
    inside = np.bincount(layout.labels[mask], minlength=layout.count + 1)[1:]
    return inside >= DOT_IN_GLYPH_FRACTION * layout.areas


@lru_cache(maxsize=32)
def _glyph_membership(layout: DotLayout) -> tuple:
    answers, members = [], []
    for answer, text, slot in candidate_texts():
        answers.append(answer)
        members.append(dots_in_mask(layout, text_mask(text, layout.size, slot)))
    return tuple(answers), np.array(members)


def split_in_two(coordinates, weights) -> tuple:
    """The dominant two-group split of points ``(N, D)`` weighted by ``weights`` (N,).

    Returns
    -------
    groups : ndarray (N,) of bool
        Membership of the second group.
    gap : float
        Distance between the two groups' weighted means (0 if there is one group).
    """
    x = np.asarray(coordinates, dtype=float)
    w = np.asarray(weights, dtype=float)
    w = w / w.sum()
    if x.ndim != 2 or len(x) != len(w):
        raise InputError(f"split_in_two needs (N, D) coordinates and N weights; got {x.shape} "
                         f"and {w.shape}")
    centred = x - w @ x
    covariance = (centred * w[:, None]).T @ centred
    scale = max(1.0, float(np.max(np.abs(x), initial=0.0)))
    if x.shape[1] == 0 or np.trace(covariance) <= (1e-12 * scale) ** 2:  # all one colour
        return np.zeros(len(x), dtype=bool), 0.0
    axis = np.linalg.eigh(covariance)[1][:, -1]
    projection = centred @ axis
    order = np.argsort(projection)
    cumulative_w = np.cumsum(w[order])[:-1]
    cumulative_p = np.cumsum((w * projection)[order])[:-1]
    with np.errstate(divide="ignore", invalid="ignore"):
        between = cumulative_p ** 2 / (cumulative_w * (1 - cumulative_w))
    k = int(np.nanargmax(between))
    groups = np.zeros(len(x), dtype=bool)
    groups[order[k + 1:]] = True
    for _ in range(_MAX_ITERATIONS):
        if groups.all() or not groups.any():
            return groups, 0.0
        means = [w[g] @ x[g] / w[g].sum() for g in (~groups, groups)]
        updated = (np.linalg.norm(x - means[1], axis=1) < np.linalg.norm(x - means[0], axis=1))
        if np.array_equal(updated, groups):
            break
        groups = updated
    if groups.all() or not groups.any():
        return groups, 0.0
    means = [w[g] @ x[g] / w[g].sum() for g in (~groups, groups)]
    return groups, float(np.linalg.norm(means[1] - means[0]))


def read_dots(layout: DotLayout, coordinates) -> Reading:
    """Read a plate from its dots' chromatic coordinates ``(N, D)`` (module notes).

    Parameters
    ----------
    layout : DotLayout
        The plate's dots (label image, areas).
    coordinates : array_like, shape (N, D)
        Each dot's coordinates in the observer's chromatic space (JND).
    """
    coordinates = np.asarray(coordinates, dtype=float)
    if coordinates.shape[0] != layout.count:
        raise InputError(f"{coordinates.shape[0]} dot colours for {layout.count} dots; give one "
                         "colour per dot")
    areas = layout.areas.astype(float)
    groups, gap = split_in_two(coordinates, areas)
    answers, members = _glyph_membership(layout)
    scores = []
    for group in (groups, ~groups):
        intersection = (members & group) @ areas
        union = (members | group) @ areas
        scores.append(intersection / union)
    scores = np.max(scores, axis=0)
    best = int(np.argmax(scores))
    match = float(scores[best])
    if gap < LEGIBILITY_THRESHOLD_JND:
        return Reading(NOTHING_READ, gap, match, answers[best], "no colour contrast")
    if match < GLYPH_MATCH_THRESHOLD:
        return Reading(NOTHING_READ, gap, match, answers[best], "no digit shape")
    return Reading(answers[best], gap, match, answers[best], "read")
