"""The reflectance cube: a hyperspectral texture as the workbench holds it in memory.

Scale
-----
- ``data`` is reflectance on 0..1 (values up to :data:`REFLECTANCE_RANGE`'s 1.5
  are accepted: fluorescent and specular texels exceed 1), ``float32``,
  shape ``(H, W, B)``: rows, columns, bands (band-interleaved-by-pixel, the
  texture's spatial layout first).
- ``wavelengths`` in nm, strictly increasing, shape ``(B,)``; any sampling that
  covers at least :data:`REQUIRED_RANGE_NM` (the colorimetry holds the end
  values outside the cube's range, as :mod:`workbench.colorimetry` does).

Every check raises :class:`workbench.errors.SpectrumFileError` naming the
cube's ``source`` (its file), the problem and the fix, so that a reader can
build the cube and let the cube say what is wrong with the file.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.errors import SpectrumFileError

__all__ = [
    "REFLECTANCE_RANGE",
    "REQUIRED_RANGE_NM",
    "ReflectanceCube",
    "check_cube_wavelengths",
]

REFLECTANCE_RANGE = (0.0, 1.5)
"""Accepted reflectance values (inclusive); outside it a cube is rejected."""

REQUIRED_RANGE_NM = (400.0, 700.0)
"""A cube must cover at least this range (nm) for colorimetry."""

_CHECK_ROWS = 64
"""Rows checked at a time, so that validating a 400 MB cube needs no 400 MB temporary."""


def check_cube_wavelengths(wavelengths, bands: int | None, source: str) -> np.ndarray:
    """Validated wavelengths (nm, float64, ``(B,)``) of a cube from ``source``.

    Parameters
    ----------
    wavelengths : array_like or None
        Band centres in nm.
    bands : int, optional
        Number of bands of the data the wavelengths belong to.
    source : str
        The file (or description) named in errors.

    Raises
    ------
    SpectrumFileError
        Missing, non-numeric, non-finite, unsorted or duplicated wavelengths;
        a count different from ``bands``; a range not covering
        :data:`REQUIRED_RANGE_NM`.
    """
    if wavelengths is None:
        raise SpectrumFileError(source, None, "the cube has no wavelengths",
                                "store the band centres in nm with the cube (ENVI header "
                                "'wavelength = {...}', or a 'wavelengths' array in .npz/.h5/.mat)")
    try:
        values = np.asarray(wavelengths, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise SpectrumFileError(source, None, "the wavelengths are not numbers",
                                "store the band centres as numbers in nm") from None
    if values.size == 0:
        raise SpectrumFileError(source, None, "the wavelength list is empty",
                                "store one band centre (nm) per band")
    if bands is not None and values.size != bands:
        raise SpectrumFileError(source, None,
                                f"shape mismatch: the data have {bands} bands but "
                                f"{values.size} wavelengths are given",
                                "give exactly one wavelength per band (and check that the cube's "
                                "last axis is the spectral one)")
    if not np.all(np.isfinite(values)):
        raise SpectrumFileError(source, None, "a wavelength is NaN or infinite",
                                "replace it with the band centre in nm")
    steps = np.diff(values)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        problem = ("appears twice" if steps[i - 1] == 0
                   else f"comes after {values[i - 1]:g} nm")
        raise SpectrumFileError(source, None,
                                f"wavelengths are not strictly increasing: band {i} "
                                f"({values[i]:g} nm) {problem}",
                                "sort the bands by increasing wavelength (and the data with them)")
    low, high = REQUIRED_RANGE_NM
    if values[0] > low or values[-1] < high:
        hint = (" (they look like µm: multiply by 1000)" if values[-1] < 10 else "")
        raise SpectrumFileError(source, None,
                                f"the wavelengths span {values[0]:g}–{values[-1]:g} nm, which does "
                                f"not cover {low:g}–{high:g} nm{hint}",
                                f"use a cube measured over at least {low:g}–{high:g} nm")
    return values


def _check_reflectance(data: np.ndarray, wavelengths: np.ndarray, source: str) -> None:
    low, high = REFLECTANCE_RANGE
    for start in range(0, data.shape[0], _CHECK_ROWS):
        block = data[start:start + _CHECK_ROWS]
        finite = np.isfinite(block)
        if not finite.all():
            row, col, band = np.argwhere(~finite)[0]
            count = int(np.count_nonzero(~finite))
            raise SpectrumFileError(
                source, None,
                f"the cube holds NaN or infinite values ({count} in rows {start}–"
                f"{start + block.shape[0] - 1} alone; first at row {start + row}, column {col}, "
                f"{wavelengths[band]:g} nm)",
                "mask or inpaint the missing texels before exporting the cube")
        bad = (block < low) | (block > high)
        if bad.any():
            row, col, band = np.argwhere(bad)[0]
            value = float(block[row, col, band])
            scale_hint = ("; if the cube is in percent divide it by 100, if it holds scaled "
                          "integers (e.g. 0–10000) divide by that scale (ENVI: set "
                          "'reflectance scale factor' in the header)") if value > high else ""
            raise SpectrumFileError(
                source, None,
                f"reflectance {value:g} at row {start + row}, column {col}, "
                f"{wavelengths[band]:g} nm is outside [{low:g}, {high:g}]",
                "store reflectance on 0..1" + scale_hint)


@dataclass(frozen=True, eq=False)
class ReflectanceCube:
    """A hyperspectral reflectance texture.

    Attributes
    ----------
    data : ndarray, shape (H, W, B), float32
        Reflectance on 0..1 (accepted up to 1.5), rows × columns × bands.
    wavelengths : ndarray, shape (B,), float64
        Band centres in nm, strictly increasing, covering 400–700 nm.
    source : str
        Where the cube comes from (a file path, or a description); errors name it.

    Raises
    ------
    SpectrumFileError
        On construction, for data that is not 3-D, has a band count different
        from the wavelengths, holds NaN/inf or reflectance outside
        :data:`REFLECTANCE_RANGE`, or wavelengths that are missing, unsorted or
        do not cover :data:`REQUIRED_RANGE_NM`.

    Examples
    --------
    >>> import numpy as np
    >>> cube = ReflectanceCube(np.full((2, 3, 101), 0.5, np.float32),
    ...                        np.arange(380, 781, 4.0), "grey card")
    >>> cube.shape
    (2, 3, 101)
    """

    data: np.ndarray
    wavelengths: np.ndarray
    source: str = "<array>"

    def __post_init__(self):
        source = str(self.source)
        object.__setattr__(self, "source", source)
        data = self.data
        if not isinstance(data, np.ndarray) or data.dtype != np.float32:
            try:
                data = np.asarray(data, dtype=np.float32)
            except (TypeError, ValueError):
                raise SpectrumFileError(source, None, "the cube data are not numbers",
                                        "store the reflectance as a numeric (H, W, B) array"
                                        ) from None
        if data.ndim != 3:
            raise SpectrumFileError(source, None,
                                    f"the cube data have shape {data.shape}; a cube is 3-D "
                                    "(rows, columns, bands)",
                                    "store the reflectance as an (H, W, B) array")
        if min(data.shape) == 0:
            raise SpectrumFileError(source, None, f"the cube is empty (shape {data.shape})",
                                    "export a cube with at least one texel and two bands")
        wavelengths = check_cube_wavelengths(self.wavelengths, data.shape[2], source)
        _check_reflectance(data, wavelengths, source)
        object.__setattr__(self, "data", data)
        object.__setattr__(self, "wavelengths", wavelengths)

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(H, W, B)``."""
        return tuple(self.data.shape)

    @property
    def height(self) -> int:
        return self.data.shape[0]

    @property
    def width(self) -> int:
        return self.data.shape[1]

    @property
    def bands(self) -> int:
        return self.data.shape[2]

    def texels(self) -> np.ndarray:
        """The reflectances as ``(H·W, B)`` (a view when the data are contiguous)."""
        return self.data.reshape(-1, self.bands)

    def __repr__(self) -> str:
        return (f"ReflectanceCube({self.height}×{self.width}×{self.bands}, "
                f"{self.wavelengths[0]:g}–{self.wavelengths[-1]:g} nm, source={self.source!r})")
