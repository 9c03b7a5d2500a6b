"""NumPy ``.npz`` cubes: arrays ``reflectance`` (H, W, B) and ``wavelengths`` (B,), nm.

Names follow :mod:`workbench.hyperspectral.variables` (other names are found by
auto-detection). Reading never unpickles (``allow_pickle=False``); writing is
uncompressed and atomic.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from workbench.errors import SpectrumFileError
from workbench.fileio import atomic_output
from workbench.hyperspectral.cube import ReflectanceCube
from workbench.hyperspectral.variables import (
    CUBE_VARIABLE,
    WAVELENGTH_VARIABLE,
    pick_cube_variables,
)

__all__ = ["read_cube_npz", "write_cube_npz"]


def read_cube_npz(path) -> ReflectanceCube:
    """Read a ``.npz`` cube (variable names: :mod:`workbench.hyperspectral.variables`).

    Raises
    ------
    SpectrumFileError
        Not a readable archive (e.g. truncated), a member that cannot be read,
        no cube array, and every check of :class:`ReflectanceCube`.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as archive:
            shapes = {}
            arrays = {}
            for name in archive.files:
                value = archive[name]
                if value.dtype.kind in "iufb":
                    arrays[name] = value
                    shapes[name] = value.shape
            cube_name, wavelength_name = pick_cube_variables(shapes, path)
            data = arrays[cube_name]
            wavelengths = None if wavelength_name is None else arrays[wavelength_name].reshape(-1)
    except SpectrumFileError:
        raise
    except (zipfile.BadZipFile, EOFError, OSError, ValueError) as error:
        raise SpectrumFileError(path, None, f"not a readable .npz archive ({error}); the file may "
                                "be truncated",
                                "copy or export the cube again") from None
    return ReflectanceCube(data, wavelengths, str(path))


def write_cube_npz(cube: ReflectanceCube, path) -> Path:
    """Write ``cube`` as an uncompressed ``.npz`` (float32 reflectance, float64 nm), atomically."""
    path = Path(path)
    with atomic_output(path) as (staged,):
        np.savez(staged, **{CUBE_VARIABLE: cube.data, WAVELENGTH_VARIABLE: cube.wavelengths})
    return path
