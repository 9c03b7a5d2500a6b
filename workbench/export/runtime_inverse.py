"""The display inverse as a runtime evaluates it: affine drive, optional 3D correction, thresholds.

Every display model here inverts as ``DAC = dac_from_drive(clip(linear_drive(XYZ), 0, 1))``
with ``dac_from_drive`` acting on each channel alone (a tone-curve inverse).
A runtime (shader, reference consumer) evaluates that as:

1. ``drive = XYZ @ XYZ_to_drive + drive_offset`` — the model's linear part
   (exact for the paper's model, ideal sRGB and separable extended models;
   for the others, the model's drive near black, where nothing else acts),
   folded into the level-2 K × 3 matrices;
2. where the model's drive is not affine in XYZ (channel interaction,
   level-dependent primaries, a residual LUT): ``drive = correction(drive)``,
   a 3D table of the model's exact drive sampled on a regular grid of the
   affine drive over ``correction_domain`` (per channel), read trilinearly
   with the affine drive clamped to the domain;
3. ``u = √clip(drive, 0, 1)`` (float32) and ``DAC = #{v : thresholds[c, v] ≤ u}``,
   the thresholds being the smallest ``u`` that gives each DAC level 1..255
   (found by bisection on the model's own ``dac_from_drive``; a level never
   reached holds :data:`UNREACHED_THRESHOLD`). A shader finds that count in
   one look-up and a step or two: ``cells[c, ⌊u·(L − 1)⌋]`` is a lower bound
   of it (:data:`CELLS` cells in ``u``), then it steps up while the next
   threshold is ≤ ``u``.

For a separable model steps 1 and 3 give the model's integer DAC except
within float32 rounding of a threshold; with a correction table the
interpolation error adds (figures in the bundle's ``display_inverse.json``).

Scale: XYZ on the display model's scale; drive 0..1; DAC integers 0..255.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.display import DisplayModel, quantize_dac
from workbench.errors import InputError

__all__ = [
    "UNREACHED_THRESHOLD",
    "CELLS",
    "DEFAULT_CORRECTION_SIZE",
    "CORRECTION_DOMAIN",
    "InverseAccuracy",
    "RuntimeDisplayInverse",
    "runtime_display_inverse",
    "runtime_inverse_accuracy",
    "sample_trilinear",
]

CELLS = 4096
"""Cells of the lower-bound table in ``u = √drive`` (at most ~0.2 DAC level per cell)."""

UNREACHED_THRESHOLD = 2.0
"""Threshold of a DAC level the display never reaches (``u`` never exceeds 1; JSON has no inf)."""

DEFAULT_CORRECTION_SIZE = 61
"""Nodes per axis of the drive-correction table: spacing 1/40 of the drive range, with nodes
on drive 0 and 1 exactly (where the clipping kinks are), 2.7 MB as float32. Measured on the
simulated headset's profile (per-channel co-drive interaction + black), integer DAC equal to
the model's own inverse on 99.97 % of random colours (49 nodes: 99.96 %, 73: 99.97 %); on an
earlier fit of the same headset, 99.74 % (49: 99.59 %; 57, whose nodes miss drive 0 and 1:
98.68 %)."""

CORRECTION_DOMAIN = (-0.25, 1.25)
"""Affine-drive range the correction table covers, per channel."""

_BISECTION_STEPS = 60


def sample_trilinear(table: np.ndarray, coordinates: np.ndarray) -> np.ndarray:
    """Trilinear interpolation of ``table`` ``(n, n, n, C)`` indexed ``[b, g, r]`` (red fastest).

    ``coordinates`` ``(..., 3)`` are (r, g, b) on 0..1 over the grid (clamped).
    float32 arithmetic, as a shader does it.
    """
    table = np.asarray(table, dtype=np.float32)
    n = table.shape[0]
    position = np.clip(np.asarray(coordinates, dtype=np.float32), 0.0, 1.0) * np.float32(n - 1)
    base = np.minimum(np.floor(position).astype(np.int64), n - 2)
    fraction = (position - base).astype(np.float32)
    r0, g0, b0 = base[..., 0], base[..., 1], base[..., 2]
    fr, fg, fb = (fraction[..., i:i + 1] for i in range(3))
    result = np.zeros(position.shape[:-1] + (table.shape[-1],), dtype=np.float32)
    for db, wb in ((0, 1 - fb), (1, fb)):
        for dg, wg in ((0, 1 - fg), (1, fg)):
            for dr, wr in ((0, 1 - fr), (1, fr)):
                result += (wb * wg * wr) * table[b0 + db, g0 + dg, r0 + dr]
    return result


@dataclass(frozen=True, eq=False)
class RuntimeDisplayInverse:
    """A display inverse in the runtime's form (module doc).

    Attributes
    ----------
    XYZ_to_drive : ndarray (3, 3)
        ``drive = XYZ @ XYZ_to_drive + drive_offset``.
    drive_offset : ndarray (3,)
    thresholds : ndarray (3, 255), float32
        Smallest ``u = √drive`` giving DAC ≥ v, v = 1..255.
    cells : ndarray (3, CELLS), int32
        A lower bound of the DAC for ``u`` in cell ``⌊u (CELLS − 1)⌋``.
    correction : ndarray (n, n, n, 3), float32, or None
        Exact drive at the affine-drive grid nodes, indexed ``[b, g, r]``.
    correction_domain : tuple of float
        Affine-drive range (low, high) of the grid, every channel.
    model : str
        The model's description.
    """

    XYZ_to_drive: np.ndarray
    drive_offset: np.ndarray
    thresholds: np.ndarray
    cells: np.ndarray
    correction: np.ndarray | None
    correction_domain: tuple[float, float]
    model: str

    def corrected_drive(self, affine_drive) -> np.ndarray:
        """Step 2: the model's drive from the affine drive (float32)."""
        drive = np.asarray(affine_drive, dtype=np.float32)
        if self.correction is None:
            return drive
        low, high = self.correction_domain
        return sample_trilinear(self.correction, (drive - np.float32(low)) / np.float32(high - low))

    def dac_from_affine_drive(self, affine_drive) -> np.ndarray:
        """Steps 2–3: integer DAC ``(..., 3)`` for affine drive ``(..., 3)``."""
        drive = self.corrected_drive(affine_drive)
        u = np.sqrt(np.clip(drive, np.float32(0.0), np.float32(1.0))).astype(np.float32)
        return np.stack([np.searchsorted(self.thresholds[c], u[..., c], side="right")
                         for c in range(3)], axis=-1)

    def dac(self, XYZ) -> np.ndarray:
        """Integer DAC ``(..., 3)`` for ``XYZ`` through all three steps."""
        drive = np.asarray(XYZ, dtype=np.float64) @ self.XYZ_to_drive + self.drive_offset
        return self.dac_from_affine_drive(drive.astype(np.float32))

    def to_json(self) -> dict:
        """The ``display_inverse.json`` body (the correction table goes to its own file)."""
        return {
            "format": "vr-colour-workbench-display-inverse", "format_version": 1,
            "model": self.model,
            "XYZ_to_drive": [float(v) for v in self.XYZ_to_drive.reshape(-1)],
            "drive_offset": [float(v) for v in self.drive_offset],
            "thresholds": [float(v) for v in self.thresholds.reshape(-1)],
            "cells": [int(v) for v in self.cells.reshape(-1)],
            "unreached_threshold": UNREACHED_THRESHOLD,
            "correction": {"size": 0, "domain": [0.0, 1.0], "file": ""}
            if self.correction is None else {
                "size": int(self.correction.shape[0]),
                "domain": [float(v) for v in self.correction_domain],
                "file": "display_drive_correction.bin"},
            "layout": {
                "XYZ_to_drive": "3 x 3 row-major: drive_j = sum_i XYZ_i * XYZ_to_drive[3 i + j] "
                                "+ drive_offset[j]",
                "thresholds": "3 x 255 channel-major: thresholds[255 c + v - 1] is the smallest "
                              "sqrt(drive) of channel c giving DAC >= v; DAC = how many of the "
                              "channel's 255 thresholds are <= sqrt(clamp(drive, 0, 1)), float32",
                "cells": f"3 x {CELLS} channel-major: a lower bound of that DAC for u in cell "
                         f"floor(u * {CELLS - 1}); start there and step up while the next "
                         "threshold (thresholds[255 c + DAC]) is <= u",
                "correction": "size 0: none (the drive is affine in XYZ). Otherwise "
                              "display_drive_correction.bin, float32 little-endian "
                              "[b][g][r][3], red fastest: the display's drive at the node whose "
                              "affine drive is domain[0] + index * (domain[1] - domain[0]) / "
                              "(size - 1), read trilinearly with the affine drive clamped to domain"},
        }


def _affine_part(display: DisplayModel) -> tuple[np.ndarray, np.ndarray]:
    offset = np.asarray(display.linear_drive(np.zeros(3)), dtype=np.float64)
    matrix = np.asarray(display.linear_drive(np.eye(3)), dtype=np.float64) - offset
    if not (np.all(np.isfinite(matrix)) and np.all(np.isfinite(offset))) or \
            abs(np.linalg.det(matrix)) < 1e-300:
        raise InputError(f"display model {display.describe()!r} has no usable linear part "
                         "(its drive near black is singular); it cannot be exported to a runtime")
    return matrix, offset


def _is_affine(display: DisplayModel, matrix: np.ndarray, offset: np.ndarray) -> bool:
    scale = float(np.max(np.abs(display.white_XYZ)))
    probe = np.random.default_rng(7).uniform(-0.2, 1.2, (256, 3)) * scale
    actual = np.asarray(display.linear_drive(probe), dtype=np.float64)
    return bool(np.allclose(actual, probe @ matrix + offset, rtol=1e-9, atol=1e-9))


def _channel_thresholds(display: DisplayModel) -> np.ndarray:
    """``(3, 255)`` float32: smallest √drive per channel whose DAC is ≥ v (v = 1..255)."""
    grid = np.linspace(0.0, 1.0, 257)
    same = np.asarray(display.dac_from_drive(np.stack([grid] * 3, axis=-1)), dtype=np.float64)
    mixed = np.asarray(display.dac_from_drive(np.stack([grid, grid[::-1], np.roll(grid, 77)],
                                                       axis=-1)), dtype=np.float64)
    expected = np.stack([same[:, 0], same[::-1, 1], np.roll(same[:, 2], 77)], axis=-1)
    if not (np.all(np.isfinite(same)) and np.allclose(mixed, expected, rtol=0, atol=1e-9)
            and np.all(np.diff(same, axis=0) >= -1e-9)):
        raise InputError(f"display model {display.describe()!r}: its tone-curve inverse is not one "
                         "non-decreasing curve per channel, which the runtime bundle needs")
    levels = np.arange(1, 256)[:, None]

    def reaches(drive):
        return quantize_dac(display.dac_from_drive(drive)) >= levels

    low, high = np.zeros((255, 3)), np.ones((255, 3))
    at_zero, at_one = reaches(low), reaches(high)
    for _ in range(_BISECTION_STEPS):
        middle = 0.5 * (low + high)
        above = reaches(middle)
        high = np.where(above, middle, high)
        low = np.where(above, low, middle)
    drive = np.where(at_zero, 0.0, high)
    u = np.sqrt(drive).astype(np.float32)
    # the float32 u must still reach the level: step up one ulp where rounding fell below
    below = quantize_dac(display.dac_from_drive(u.astype(np.float64) ** 2)) < levels
    u = np.where(below & ~at_zero, np.nextafter(u, np.float32(2.0)), u)
    return np.where(at_one | at_zero, u, np.float32(UNREACHED_THRESHOLD)).T.astype(np.float32)


def runtime_display_inverse(display: DisplayModel, *, correction_size: int = DEFAULT_CORRECTION_SIZE
                            ) -> RuntimeDisplayInverse:
    """The runtime form of ``display``'s inverse (module doc).

    Parameters
    ----------
    display : DisplayModel
        Any registered model whose ``dac_from_drive`` is per channel and non-decreasing.
    correction_size : int
        Nodes per axis of the correction table (used only when the drive is not affine).

    Raises
    ------
    InputError
        The model's tone-curve inverse is not per channel, or its linear part is singular.
    """
    if correction_size < 2:
        raise InputError(f"correction_size={correction_size}: need at least 2 nodes per axis")
    # (correction_size - 1) a multiple of 6 puts nodes on drive 0 and 1 of CORRECTION_DOMAIN
    matrix, offset = _affine_part(display)
    thresholds = _channel_thresholds(display)
    correction = None
    if not _is_affine(display, matrix, offset):
        low, high = CORRECTION_DOMAIN
        nodes = np.linspace(low, high, correction_size)
        b, g, r = np.meshgrid(nodes, nodes, nodes, indexing="ij")
        affine = np.stack([r, g, b], axis=-1)                        # [b, g, r] -> (r, g, b)
        XYZ = (affine - offset) @ np.linalg.inv(matrix)
        with np.errstate(all="ignore"):
            exact = np.asarray(display.linear_drive(XYZ.reshape(-1, 3)), dtype=np.float64)
        if not np.all(np.isfinite(exact)):
            raise InputError(f"display model {display.describe()!r}: its inverse is not finite "
                             "over the drive range; it cannot be exported to a runtime")
        correction = exact.reshape(affine.shape).astype(np.float32)
    # a thousandth of a cell below each cell's lower edge, so float rounding of u keeps a lower bound
    edges = ((np.arange(CELLS) - 1e-3) / (CELLS - 1)).astype(np.float64)
    cells = np.stack([np.searchsorted(thresholds[c].astype(np.float64), edges, side="right")
                      for c in range(3)]).astype(np.int32)
    return RuntimeDisplayInverse(XYZ_to_drive=matrix, drive_offset=offset, thresholds=thresholds,
                                 cells=cells, correction=correction, correction_domain=CORRECTION_DOMAIN,
                                 model=display.describe())


@dataclass(frozen=True)
class InverseAccuracy:
    """How often the runtime's integer DAC equals the model's own (:meth:`DisplayModel.inverse_rgb8`).

    Measured on ``samples`` colours the display shows for uniformly random DAC
    values: ``identical`` is the share (0..1) with the same integer DAC in all
    three channels, ``max_counts`` the largest difference in any channel.
    """

    identical: float
    max_counts: int
    samples: int

    def to_json(self) -> dict:
        return {"identical_share": round(self.identical, 5), "max_counts": self.max_counts,
                "n": self.samples,
                "protocol": "colours of uniformly random DAC values, runtime integer DAC vs the "
                            "model's own inverse"}


def runtime_inverse_accuracy(inverse: RuntimeDisplayInverse, display: DisplayModel, *,
                             samples: int = 20000, seed: int = 0) -> InverseAccuracy:
    """Measure ``inverse`` against ``display``'s own inverse (:class:`InverseAccuracy`)."""
    XYZ = display.forward(np.random.default_rng(seed).uniform(0.0, 255.0, (samples, 3)))
    difference = np.abs(inverse.dac(XYZ) - display.inverse_rgb8(XYZ)).max(axis=-1)
    return InverseAccuracy(float(np.mean(difference == 0)), int(difference.max()), samples)
