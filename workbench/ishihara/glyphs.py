"""The digit font of the plates: thick strokes along polylines, drawn with NumPy.

Each digit is a few polylines (straight strokes and elliptic arcs) in a cell
of unit height and :data:`CELL_ASPECT` width, drawn as every pixel within half
a stroke width of them. The figures of the real Ishihara plates are strokes
two or three dots wide; so are these. No font file and no Pillow: the same
glyphs serve to build the plates and, as templates, to read them, so a
reading model cannot be fooled by a rendering it does not know.

Layouts (:data:`LAYOUT_SLOTS`): a one-digit plate puts its digit in the
``"centre"`` slot; a two-digit plate its digits in ``"left"`` and ``"right"``.
Coordinates are pixels of the plate image, the plate disc centred.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from workbench.errors import InputError

__all__ = [
    "DIGIT_HEIGHT_FRACTION",
    "CELL_ASPECT",
    "STROKE_FRACTION",
    "LAYOUT_SLOTS",
    "digit_strokes",
    "slots_for",
    "text_mask",
]

DIGIT_HEIGHT_FRACTION = 0.50
"""Digit height as a fraction of the plate image size."""

CELL_ASPECT = 0.62
"""Width of a digit cell over its height."""

STROKE_FRACTION = 0.16
"""Stroke width as a fraction of the digit height."""

_PAIR_GAP = 0.20
"""Gap between the two cells of a pair, as a fraction of the digit height."""

LAYOUT_SLOTS = ("centre", "left", "right")


def _arc(cx, cy, rx, ry, start_deg, end_deg, n=24):
    """Points of an elliptic arc (angles in degrees, 0 = right, 90 = down)."""
    angles = np.radians(np.linspace(start_deg, end_deg, n))
    return np.column_stack([cx + rx * np.cos(angles), cy + ry * np.sin(angles)])


def _line(*points):
    return np.array(points, dtype=float)


_DIGITS = {
    "0": (_arc(0.5, 0.5, 0.42, 0.46, 0, 360, 48),),
    "1": (_line((0.22, 0.22), (0.56, 0.03), (0.56, 0.97)),),
    "2": (np.vstack([_arc(0.5, 0.29, 0.40, 0.26, 195, 380),
                     _line((0.86, 0.42), (0.08, 0.97), (0.95, 0.97))]),),
    "3": (_arc(0.48, 0.27, 0.38, 0.23, 200, 450), _arc(0.48, 0.73, 0.44, 0.25, 270, 520)),
    "4": (_line((0.72, 0.97), (0.72, 0.03), (0.04, 0.68), (0.97, 0.68)),),
    "5": (np.vstack([_line((0.88, 0.03), (0.16, 0.03), (0.10, 0.47)),
                     _arc(0.48, 0.69, 0.42, 0.28, 225, 500)]),),
    "6": (_arc(0.5, 0.69, 0.42, 0.28, 0, 360, 48),
          np.vstack([_line((0.86, 0.10)), _arc(0.62, 0.58, 0.54, 0.55, 262, 180, 16)])),
    "7": (_line((0.04, 0.03), (0.96, 0.03), (0.38, 0.97)),),
    "8": (_arc(0.5, 0.26, 0.34, 0.23, 0, 360, 40), _arc(0.5, 0.73, 0.42, 0.25, 0, 360, 40)),
    "9": (_arc(0.5, 0.31, 0.42, 0.28, 0, 360, 48),
          np.vstack([_arc(0.38, 0.42, 0.54, 0.55, 0, 82, 16), _line((0.14, 0.90))])),
}


def digit_strokes(digit: str) -> tuple:
    """The polylines of ``digit`` in its unit cell (x right, y down, height 1)."""
    try:
        strokes = _DIGITS[digit]
    except KeyError:
        raise InputError(f"no glyph for {digit!r}; plates show the digits 0–9") from None
    return tuple(s * [CELL_ASPECT, 1.0] for s in strokes)


def slots_for(text: str) -> tuple:
    """The layout slots of the characters of ``text`` (one or two digits)."""
    if len(text) == 1:
        return ("centre",)
    if len(text) == 2:
        return ("left", "right")
    raise InputError(f"plate text {text!r}: a plate shows one or two digits")


def _cell_origin(slot: str, size: int) -> tuple:
    height = DIGIT_HEIGHT_FRACTION * size
    width = CELL_ASPECT * height
    top = (size - height) / 2.0
    centre = size / 2.0
    left = {"centre": centre - width / 2.0,
            "left": centre - _PAIR_GAP * height / 2.0 - width,
            "right": centre + _PAIR_GAP * height / 2.0}
    if slot not in left:
        raise InputError(f"unknown layout slot {slot!r}; use one of {LAYOUT_SLOTS}")
    return left[slot], top, height


def _distance_to_polyline(px: np.ndarray, py: np.ndarray, points: np.ndarray) -> np.ndarray:
    best = np.full(px.shape, np.inf)
    for (x0, y0), (x1, y1) in zip(points[:-1], points[1:]):
        dx, dy = x1 - x0, y1 - y0
        length2 = dx * dx + dy * dy
        t = 0.0 if length2 == 0 else np.clip(((px - x0) * dx + (py - y0) * dy) / length2, 0, 1)
        best = np.minimum(best, np.hypot(px - (x0 + t * dx), py - (y0 + t * dy)))
    if len(points) == 1:
        best = np.hypot(px - points[0, 0], py - points[0, 1])
    return best


@lru_cache(maxsize=512)
def _glyph_mask(digit: str, slot: str, size: int) -> np.ndarray:
    left, top, height = _cell_origin(slot, size)
    stroke = STROKE_FRACTION * height
    margin = int(np.ceil(stroke))
    x0, y0 = int(np.floor(left)) - margin, int(np.floor(top)) - margin
    x1 = int(np.ceil(left + CELL_ASPECT * height)) + margin
    y1 = int(np.ceil(top + height)) + margin
    ys, xs = np.mgrid[max(y0, 0):min(y1, size), max(x0, 0):min(x1, size)]
    px, py = xs + 0.5, ys + 0.5
    distance = np.full(px.shape, np.inf)
    for points in digit_strokes(digit):
        distance = np.minimum(distance, _distance_to_polyline(px, py, points * height + [left, top]))
    mask = np.zeros((size, size), dtype=bool)
    mask[ys, xs] = distance <= stroke / 2.0
    mask.setflags(write=False)
    return mask


def text_mask(text: str, size: int, slot: str | None = None) -> np.ndarray:
    """Boolean image ``(size, size)`` of ``text`` drawn in the plate's layout.

    Parameters
    ----------
    text : str
        One or two digits.
    size : int
        Plate image size in pixels.
    slot : str, optional
        Draw a single digit in this slot instead of the one its length implies
        (e.g. ``"right"``: what remains of a pair when the left digit vanishes).
    """
    size = int(size)
    if size < 32:
        raise InputError(f"plate size {size} px is too small for legible digits; use 32 px or more")
    slots = (slot,) if slot is not None else slots_for(text)
    if len(slots) != len(text):
        raise InputError(f"text {text!r} does not fit slot {slot!r}; give one digit per slot")
    mask = np.zeros((size, size), dtype=bool)
    for character, character_slot in zip(text, slots):
        mask |= _glyph_mask(character, character_slot, size)
    return mask
