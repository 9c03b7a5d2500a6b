"""A display inverse (XYZ → integer DAC) as an affine map plus per-channel tables.

For a display model whose :meth:`~workbench.display.DisplayModel.linear_drive`
is affine in XYZ and whose :meth:`~workbench.display.DisplayModel.dac_from_drive`
acts on each channel alone and is non-decreasing (the paper's gamma-matrix
model, ideal sRGB, any per-channel tone curve), the integer DAC a texel gets,
``quantize_dac(dac_from_drive(clip(drive, 0, 1)))``, is a step function of
one channel's drive with at most 255 steps. It is stored exactly as the
*thresholds* where each DAC level begins, plus a uniform table that gives a
lower bound of the DAC in one look-up; at most a step or two of comparison
then lands on the exact level. Both are indexed by ``u = √drive``: a power-law
or sRGB curve is steep near black in ``drive`` but gentle in ``u``, so a
4096-cell table rarely needs more than one comparison.

Exactness: the tables give the same integer DAC as the model's own inverse
except where a drive lies within float32 rounding of a threshold.

Models that are not separable (3D-LUT residuals, channel interactions) raise
:class:`InputError` here; the level-2 relighting then uses the model's own
inverse (:func:`workbench.hyperspectral.relight.relight_texels`, kernel
``"numpy"``).

For the compiled kernel the same count is re-cut into :class:`DacCells`
(:func:`dac_cells`): cells of ``u`` fine enough that each holds at most one
threshold value, so that one look-up and one comparison give the DAC — and,
folded with a light's texel table (:meth:`DacCells.texel_cells`), the level-2
texel. Any thresholds in this form will do: this module's, or a runtime
bundle's (:class:`workbench.export.runtime_inverse.RuntimeDisplayInverse`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.display import DisplayModel, quantize_dac
from workbench.errors import InputError

__all__ = [
    "DEFAULT_LUT_CELLS",
    "ChannelInverseLUT",
    "DacCells",
    "channel_inverse_lut",
    "dac_cells",
    "is_channel_separable",
]

DEFAULT_LUT_CELLS = 4096
"""Cells of the ``u = √drive`` table (16 KB per channel as int32)."""

_BISECTION_STEPS = 64


@dataclass(frozen=True, eq=False)
class ChannelInverseLUT:
    """The inverse of a separable display as tables (module doc).

    Attributes
    ----------
    XYZ_to_drive : ndarray (3, 3)
        ``drive = XYZ @ XYZ_to_drive + drive_offset`` (unclipped linear drive).
    drive_offset : ndarray (3,)
    thresholds : ndarray (3, 257), float32
        ``thresholds[c, v]`` is the smallest ``u = √drive`` of channel ``c``
        that gives DAC ``v`` or more (v = 1..255); ``[c, 0] = −inf`` and
        ``[c, 256] = +inf`` are sentinels; ``+inf`` also marks a level the
        display never reaches.
    cell_dac : ndarray (3, L), int32
        A lower bound of the DAC for ``u`` in cell ``⌊u (L − 1)⌋``.
    """

    XYZ_to_drive: np.ndarray
    drive_offset: np.ndarray
    thresholds: np.ndarray
    cell_dac: np.ndarray

    def dac_from_drive(self, drive) -> np.ndarray:
        """Integer DAC ``(..., 3)`` for linear drive ``(..., 3)`` through the thresholds."""
        u = np.sqrt(np.clip(np.asarray(drive, dtype=np.float64), 0.0, 1.0)).astype(np.float32)
        return np.stack([np.searchsorted(self.thresholds[c, 1:256], u[..., c], side="right")
                         for c in range(3)], axis=-1)

    def dac(self, XYZ) -> np.ndarray:
        """Integer DAC ``(..., 3)`` for ``XYZ`` (the display's scale)."""
        return self.dac_from_drive(np.asarray(XYZ, dtype=np.float64) @ self.XYZ_to_drive
                                   + self.drive_offset)


def _affine_drive(display: DisplayModel) -> tuple[np.ndarray, np.ndarray] | None:
    offset = np.asarray(display.linear_drive(np.zeros(3)), dtype=np.float64)
    matrix = np.asarray(display.linear_drive(np.eye(3)), dtype=np.float64) - offset
    scale = float(np.max(np.abs(display.white_XYZ)))
    probe = np.random.default_rng(7).uniform(-0.2, 1.2, (64, 3)) * scale
    predicted = probe @ matrix + offset
    actual = np.asarray(display.linear_drive(probe), dtype=np.float64)
    if not np.allclose(actual, predicted, rtol=1e-9, atol=1e-9):
        return None
    return matrix, offset


def _separable_monotone(display: DisplayModel) -> bool:
    grid = np.linspace(0.0, 1.0, 257)
    same = np.asarray(display.dac_from_drive(np.stack([grid] * 3, axis=-1)), dtype=np.float64)
    mixed_drive = np.stack([grid, grid[::-1], np.roll(grid, 77)], axis=-1)
    mixed = np.asarray(display.dac_from_drive(mixed_drive), dtype=np.float64)
    expected = np.stack([same[:, 0], same[::-1, 1], np.roll(same[:, 2], 77)], axis=-1)
    return bool(np.all(np.isfinite(same)) and np.allclose(mixed, expected, rtol=0, atol=1e-9)
                and np.all(np.diff(same, axis=0) >= -1e-9))


def is_channel_separable(display: DisplayModel) -> bool:
    """Whether ``display``'s inverse is an affine map then a non-decreasing per-channel curve."""
    return _affine_drive(display) is not None and _separable_monotone(display)


def _drive_thresholds(display: DisplayModel) -> np.ndarray:
    """``(255, 3)``: the smallest drive in [0, 1] whose DAC is ≥ v (v = 1..255), +inf if none."""
    levels = np.arange(1, 256)[:, None]

    def reaches(drive):
        return quantize_dac(display.dac_from_drive(drive)) >= levels

    low = np.zeros((255, 3))
    high = np.ones((255, 3))
    at_zero = reaches(low)
    at_one = reaches(high)
    for _ in range(_BISECTION_STEPS):
        middle = 0.5 * (low + high)
        above = reaches(middle)
        high = np.where(above, middle, high)
        low = np.where(above, low, middle)
    return np.where(at_zero, 0.0, np.where(at_one, high, np.inf))


def channel_inverse_lut(display: DisplayModel, cells: int = DEFAULT_LUT_CELLS) -> ChannelInverseLUT:
    """Tables of ``display``'s inverse (module doc); raises for a non-separable model.

    Parameters
    ----------
    display : DisplayModel
    cells : int
        Cells of the ``√drive`` table (at least 2).

    Raises
    ------
    InputError
        The model's drive is not affine in XYZ, or its tone curve is not
        per-channel and non-decreasing.
    """
    if cells < 2:
        raise InputError(f"a channel table needs at least 2 cells; got {cells}")
    affine = _affine_drive(display)
    if affine is None or not _separable_monotone(display):
        raise InputError(f"display model {display.describe()!r} is not separable per channel "
                         "(affine drive, then one non-decreasing curve per channel); relight it "
                         "with kernel 'numpy', which uses the model's own inverse")
    matrix, offset = affine
    drive_thresholds = _drive_thresholds(display)                     # (255, 3)
    u_thresholds = np.sqrt(drive_thresholds).T.astype(np.float32)    # (3, 255)
    thresholds = np.empty((3, 257), dtype=np.float32)
    thresholds[:, 0], thresholds[:, 256] = -np.inf, np.inf
    thresholds[:, 1:256] = u_thresholds
    # Lower bound for a cell: thresholds passed a thousandth of a cell before its lower edge.
    edges = (np.arange(cells) - 1e-3) / (cells - 1)
    cell_dac = np.stack([np.searchsorted(u_thresholds[c].astype(np.float64), edges, side="right")
                         for c in range(3)]).astype(np.int32)
    return ChannelInverseLUT(XYZ_to_drive=matrix, drive_offset=offset,
                             thresholds=np.ascontiguousarray(thresholds),
                             cell_dac=np.ascontiguousarray(cell_dac))


MIN_DAC_CELLS = 512
"""Fewest cells :func:`dac_cells` tries (3 × 512 packed entries, 12 KB: in L1 cache)."""

MAX_DAC_CELLS = 1 << 16
"""Most cells :func:`dac_cells` tries before giving up on a curve (two thresholds closer
than this resolves)."""


@dataclass(frozen=True, eq=False)
class DacCells:
    """Integer DAC from ``u = √drive`` in one look-up and one comparison, per channel.

    ``u`` (float32, 0..1) falls in cell ``j = ⌊u (L − 1)⌋`` (float32
    arithmetic). Each cell, widened by the rounding of that product, holds at
    most one distinct threshold value ``threshold[c, j]`` (+inf: none); the DAC
    is ``below[c, j]`` for ``u`` under it and ``above[c, j]`` at or over it —
    exactly the number of thresholds ``≤ u``, as a runtime counts them.

    Attributes
    ----------
    threshold : ndarray (3, L), float32
    below, above : ndarray (3, L), int32
    thresholds : ndarray (3, 255), float32
        The sorted thresholds the cells were cut from (level ``v`` starts at
        ``thresholds[c, v − 1]``).
    """

    threshold: np.ndarray
    below: np.ndarray
    above: np.ndarray
    thresholds: np.ndarray

    @property
    def cells(self) -> int:
        """L, the cells per channel."""
        return self.threshold.shape[1]

    def dac(self, u) -> np.ndarray:
        """Integer DAC ``(..., 3)`` for ``u`` ``(..., 3)`` (float32, 0..1) through the cells."""
        u = np.asarray(u, dtype=np.float32)
        cell = (u * np.float32(self.cells - 1)).astype(np.int64)
        channels = np.arange(3)
        return np.where(u >= self.threshold[channels, cell], self.above[channels, cell],
                        self.below[channels, cell])

    def texel_cells(self, texel_table: np.ndarray) -> np.ndarray:
        """``(3, L)`` uint64 packed per cell for the compiled kernel: the threshold's float32
        bits (low 32 bits), the texel below it (bits 32–39) and at or above it (40–47),
        from a light's ``(3, 256)`` level-2 texel table."""
        table = np.asarray(texel_table, dtype=np.uint64)
        channels = np.arange(3)[:, None]
        bits = self.threshold.view(np.uint32).astype(np.uint64)
        return np.ascontiguousarray(bits | (table[channels, self.below] << np.uint64(32))
                                    | (table[channels, self.above] << np.uint64(40)))

    def reach_limits(self, levels) -> np.ndarray:
        """``(3,)`` float32: the smallest ``u`` whose DAC is ≥ ``levels[c]`` per channel
        (−inf for level 0, +inf for 256 or a level never reached)."""
        limits = np.empty(3, dtype=np.float32)
        for channel, level in enumerate(np.asarray(levels, dtype=np.int64)):
            if level <= 0:
                limits[channel] = -np.inf
            elif level > 255 or not self.thresholds[channel, level - 1] <= 1.0:
                limits[channel] = np.inf
            else:
                limits[channel] = self.thresholds[channel, level - 1]
        return limits


def dac_cells(thresholds) -> DacCells | None:
    """:class:`DacCells` of sorted per-channel thresholds ``(3, 255)`` (the smallest
    ``u = √drive`` of each DAC level 1..255; a value above 1, or +inf, for a level never
    reached); None if the thresholds are not sorted or two distinct ones lie closer than
    :data:`MAX_DAC_CELLS` cells resolve.

    Cells double from :data:`MIN_DAC_CELLS` until every one, widened by a thousandth of
    a cell plus the float32 rounding of ``u (L − 1)``, holds at most one distinct
    threshold value.
    """
    values = np.asarray(thresholds, dtype=np.float32)
    if values.shape != (3, 255) or np.any(np.isnan(values)) or np.any(np.diff(values, axis=1) < 0):
        return None
    exact = values.astype(np.float64)
    cells = MIN_DAC_CELLS
    while cells <= MAX_DAC_CELLS:
        pad = 1e-3 + cells * 2.0 ** -22      # |float32 u·(L−1) − u·(L−1)| ≤ L·2⁻²⁴ cells
        index = np.arange(cells, dtype=np.float64)
        low, high = (index - pad) / (cells - 1), (index + 1 + pad) / (cells - 1)
        threshold = np.empty((3, cells), dtype=np.float32)
        below = np.empty((3, cells), dtype=np.int32)
        above = np.empty((3, cells), dtype=np.int32)
        for channel in range(3):
            row = exact[channel]
            base = np.searchsorted(row, low, side="right")         # thresholds ≤ the cell's low end
            top = np.searchsorted(row, high, side="right")         # … ≤ its high end
            following = np.where(base < 255, row[np.minimum(base, 254)], np.inf)
            reached = np.searchsorted(row, following, side="right")  # every threshold equal to it
            if np.any(top > reached):
                break
            threshold[channel] = following
            below[channel] = base
            above[channel] = np.minimum(reached, 255)
        else:
            return DacCells(threshold=threshold, below=below, above=above,
                            thresholds=np.ascontiguousarray(values))
        cells *= 2
    return None
