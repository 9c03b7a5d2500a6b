"""Cube files: a registry of formats by suffix and one reader/writer dispatcher.

=============  =====================================  ==========================
suffix         format                                 module
=============  =====================================  ==========================
``.hdr``       ENVI header + raw data (``spectral``)  :mod:`.envi`
``.npz``       NumPy archive                          :mod:`.npz`
``.h5/.hdf5``  HDF5 (h5py)                            :mod:`.hdf5`
``.mat``       MATLAB v5 (scipy) or v7.3 (h5py)       :mod:`.matlab`
=============  =====================================  ==========================

Every reader returns a validated :class:`ReflectanceCube` (errors:
:class:`workbench.errors.SpectrumFileError`, naming the file, the problem and
the fix); every writer is atomic (:func:`workbench.fileio.atomic_output`). Variable names inside
container formats: :mod:`.variables`. ``read_cube(path, wavelengths=...)``
resamples to other wavelengths, e.g. the working 380–780 nm at 1 nm.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from workbench.errors import SpectrumFileError
from workbench.hyperspectral.cube import ReflectanceCube
from workbench.hyperspectral.envi import read_cube_envi, write_cube_envi
from workbench.hyperspectral.hdf5 import read_cube_hdf5, write_cube_hdf5
from workbench.hyperspectral.matlab import read_cube_mat, write_cube_mat
from workbench.hyperspectral.npz import read_cube_npz, write_cube_npz
from workbench.hyperspectral.resampling import resample_cube

__all__ = [
    "CubeFormat",
    "CUBE_FORMATS",
    "cube_format",
    "read_cube",
    "write_cube",
]


@dataclass(frozen=True)
class CubeFormat:
    """One cube file format: how to read it and how to write it."""

    name: str
    read: Callable[..., ReflectanceCube]
    write: Callable[..., Path]
    description: str


_ENVI = CubeFormat("ENVI", read_cube_envi, write_cube_envi,
                   "ENVI .hdr header + .img data (the 'spectral' package)")
_NPZ = CubeFormat("NumPy", read_cube_npz, write_cube_npz, "NumPy .npz archive")
_HDF5 = CubeFormat("HDF5", read_cube_hdf5, write_cube_hdf5, "HDF5 (h5py)")
_MAT = CubeFormat("MATLAB", read_cube_mat, write_cube_mat, "MATLAB .mat, v5 or v7.3")

CUBE_FORMATS: dict[str, CubeFormat] = {
    ".hdr": _ENVI,
    ".npz": _NPZ,
    ".h5": _HDF5,
    ".hdf5": _HDF5,
    ".mat": _MAT,
}
"""File suffix (lower case) → :class:`CubeFormat`."""


def cube_format(path) -> CubeFormat:
    """The format of ``path`` by its suffix; an unknown suffix raises an error listing the known ones."""
    path = Path(path)
    try:
        return CUBE_FORMATS[path.suffix.lower()]
    except KeyError:
        known = ", ".join(CUBE_FORMATS)
        hint = " (for ENVI give the .hdr header, not the data file)" if path.suffix.lower() in (
            ".img", ".dat", ".raw", ".bsq", ".bil", ".bip") else ""
        raise SpectrumFileError(path, None, f"unknown cube format {path.suffix or '(no suffix)'!r}"
                                f"{hint}", f"use a file ending in one of {known}") from None


def read_cube(path, *, wavelengths=None) -> ReflectanceCube:
    """Read a reflectance cube, optionally resampled to ``wavelengths`` (nm).

    Parameters
    ----------
    path : path-like
        A file of one of :data:`CUBE_FORMATS`.
    wavelengths : array_like, optional
        Resample to these wavelengths (linear, ends held; e.g.
        :data:`workbench.colorimetry.WORKING_WAVELENGTHS`). Default: the file's own bands.

    Returns
    -------
    ReflectanceCube

    Raises
    ------
    SpectrumFileError
        Unknown suffix, missing file, and every format's and the cube's checks.
    """
    path = Path(path)
    file_format = cube_format(path)
    if not path.is_file():
        raise SpectrumFileError(path, None, "no such file", "check the path")
    cube = file_format.read(path)
    if wavelengths is not None:
        cube = resample_cube(cube, wavelengths)
    return cube


def write_cube(cube: ReflectanceCube, path, **options) -> Path:
    """Write ``cube`` to ``path`` in the format its suffix names, atomically.

    ``options`` go to the format's writer (``.mat``: ``version="auto"|"5"|"7.3"``).
    """
    return cube_format(path).write(cube, Path(path), **options)
