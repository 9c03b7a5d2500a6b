"""Packed, non-overlapping dots of varying size inside the plate disc (seeded).

Random sequential adsorption in passes of decreasing radius: each pass throws
candidate dots of one radius at random positions inside the disc and keeps
those whose disc, grown by the gap, covers no pixel already taken. Large dots
go first, small ones fill the gaps, as on a printed Ishihara plate. The
result depends only on the size and the seed.

Scale: pixels of a square plate image; the plate disc is centred and its
radius is :data:`DISC_RADIUS_FRACTION` of the image size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.errors import InputError

__all__ = [
    "DISC_RADIUS_FRACTION",
    "DOT_RADIUS_FRACTIONS",
    "DotLayout",
    "pack_dots",
]

DISC_RADIUS_FRACTION = 0.48
"""Plate disc radius over image size."""

DOT_RADIUS_FRACTIONS = (0.011, 0.032)
"""Smallest and largest dot radius over image size (about 2–6 px on a 192 px plate)."""

_GAP_FRACTION = 0.004
_PASSES = 6
_TRIES_PER_PASS_AREA = 2.5
"""Candidates per pass, per dot that would tile the disc at that pass's radius."""


@dataclass(frozen=True, eq=False)
class DotLayout:
    """Dots packed in a plate.

    Attributes
    ----------
    size : int
        Image size in pixels (square).
    labels : ndarray, shape (size, size), uint16
        Dot id (1 … N) of each pixel; 0 is paper.
    centres : ndarray, shape (N, 2)
        Dot centres (x, y) in pixels.
    radii : ndarray, shape (N,)
        Dot radii in pixels.
    """

    size: int
    labels: np.ndarray
    centres: np.ndarray
    radii: np.ndarray

    @property
    def count(self) -> int:
        return len(self.radii)

    @property
    def areas(self) -> np.ndarray:
        """Pixels of each dot (N,)."""
        return np.bincount(self.labels.ravel(), minlength=self.count + 1)[1:]


def _disc_offsets(radius: float) -> tuple:
    r = int(np.ceil(radius))
    dy, dx = np.mgrid[-r:r + 1, -r:r + 1]
    keep = dx ** 2 + dy ** 2 <= radius ** 2
    return dy[keep], dx[keep]


def pack_dots(size: int, seed: int) -> DotLayout:
    """Pack dots into the plate disc of a ``size`` × ``size`` image.

    Parameters
    ----------
    size : int
        Image size in pixels (64 or more).
    seed : int
        Seed of the positions and sizes.

    Returns
    -------
    DotLayout
    """
    size = int(size)
    if size < 64:
        raise InputError(f"plate size {size} px is too small to pack dots; use 64 px or more")
    rng = np.random.default_rng(seed)
    centre = size / 2.0
    disc = DISC_RADIUS_FRACTION * size
    gap = max(1.0, _GAP_FRACTION * size)
    r_min, r_max = (f * size for f in DOT_RADIUS_FRACTIONS)
    taken = np.zeros((size, size), dtype=bool)
    labels = np.zeros((size, size), dtype=np.uint16)
    centres, radii = [], []
    for radius in np.geomspace(r_max, r_min, _PASSES):
        grown_dy, grown_dx = _disc_offsets(radius + gap)
        dot_dy, dot_dx = _disc_offsets(radius)
        tries = int(_TRIES_PER_PASS_AREA * (disc / radius) ** 2)
        # uniform in the part of the disc where the whole dot fits
        reach = disc - radius
        rho = reach * np.sqrt(rng.random(tries))
        theta = 2 * np.pi * rng.random(tries)
        jitter = rng.uniform(0.85, 1.0, tries)
        xs_all = np.rint(centre + rho * np.cos(theta)).astype(int).tolist()
        ys_all = np.rint(centre + rho * np.sin(theta)).astype(int).tolist()
        for cx, cy, scale in zip(xs_all, ys_all, jitter.tolist()):
            if taken[cy, cx]:  # cheap early rejection: the centre itself is taken
                continue
            ys, xs = cy + grown_dy, cx + grown_dx
            inside = (ys >= 0) & (ys < size) & (xs >= 0) & (xs < size)
            if taken[ys[inside], xs[inside]].any():
                continue
            r = radius * scale
            keep = dot_dy ** 2 + dot_dx ** 2 <= r ** 2
            ys, xs = cy + dot_dy[keep], cx + dot_dx[keep]
            taken[ys, xs] = True
            centres.append((cx, cy))
            radii.append(r)
            labels[ys, xs] = len(radii)
    if len(radii) >= np.iinfo(np.uint16).max:
        raise InputError(f"plate size {size} px packs too many dots for 16-bit labels; use a "
                         "smaller plate")
    return DotLayout(size=size, labels=labels, centres=np.array(centres, dtype=float),
                     radii=np.array(radii))
