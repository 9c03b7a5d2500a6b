"""HDF5 cubes (``.h5``/``.hdf5``) through h5py; also the reader under MATLAB v7.3 files.

Layout: top-level datasets ``reflectance`` (H, W, B) and ``wavelengths`` (B,),
nm (names: :mod:`workbench.hyperspectral.variables`; auto-detected otherwise).
The wavelengths may instead be an attribute ``wavelengths`` of the cube
dataset; a ``units``/``wavelength_units`` attribute of ``µm`` (or ``um``,
``micrometers``) is converted to nm. MATLAB v7.3 files are HDF5 with the axes
stored in reverse (column-major) order; :func:`read_hdf5_cube` undoes that when
asked to.

References
----------
The HDF Group, HDF5 file format; h5py documentation (``h5py.File``,
``userblock_size``).
"""

from __future__ import annotations

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

__all__ = ["read_cube_hdf5", "write_cube_hdf5", "read_hdf5_cube"]

_MICROMETRE_UNITS = ("um", "µm", "micrometers", "micrometres", "micrometer", "micrometre",
                     "microns", "micron")


def _units_factor(*attribute_sets) -> float:
    for attributes in attribute_sets:
        for key in ("wavelength_units", "units"):
            if key in attributes:
                value = attributes[key]
                value = value.decode() if isinstance(value, bytes) else str(value)
                if value.strip().lower() in _MICROMETRE_UNITS:
                    return 1000.0
                return 1.0
    return 1.0


def read_hdf5_cube(path, *, matlab_axes: bool = False) -> ReflectanceCube:
    """Read a cube from an HDF5 file; ``matlab_axes`` reverses stored axes (MATLAB v7.3).

    Raises
    ------
    SpectrumFileError
        Not a readable HDF5 file (e.g. truncated), no cube dataset, and every
        check of :class:`ReflectanceCube`.
    """
    import h5py

    path = Path(path)
    kind = "MATLAB v7.3" if matlab_axes else "HDF5"
    try:
        with h5py.File(path, "r") as handle:
            datasets = {name: item for name, item in handle.items()
                        if isinstance(item, h5py.Dataset) and item.dtype.kind in "iufb"}
            shapes = {name: (tuple(reversed(item.shape)) if matlab_axes else item.shape)
                      for name, item in datasets.items()}
            cube_name, wavelength_name = pick_cube_variables(shapes, path)
            cube_dataset = datasets[cube_name]
            data = np.asarray(cube_dataset[()], dtype=np.float32)
            if matlab_axes:
                data = np.ascontiguousarray(np.transpose(data))
            wavelengths = None
            factor = 1.0
            if wavelength_name is not None:
                wavelength_dataset = datasets[wavelength_name]
                wavelengths = np.asarray(wavelength_dataset[()], dtype=np.float64).reshape(-1)
                factor = _units_factor(wavelength_dataset.attrs, cube_dataset.attrs, handle.attrs)
            else:
                for key in ("wavelengths", "wavelength"):
                    if key in cube_dataset.attrs:
                        wavelengths = np.asarray(cube_dataset.attrs[key], dtype=np.float64).reshape(-1)
                        factor = _units_factor(cube_dataset.attrs, handle.attrs)
                        break
    except SpectrumFileError:
        raise
    except (OSError, KeyError, ValueError, TypeError) as error:
        raise SpectrumFileError(path, None, f"not a readable {kind} file ({error}); it may be "
                                "truncated", "copy or export the cube again") from None
    if wavelengths is not None:
        wavelengths = wavelengths * factor
    return ReflectanceCube(data, wavelengths, str(path))


def read_cube_hdf5(path) -> ReflectanceCube:
    """Read an HDF5 cube (``reflectance`` (H, W, B) and ``wavelengths`` (B,) in nm)."""
    return read_hdf5_cube(path, matlab_axes=False)


def write_cube_hdf5(cube: ReflectanceCube, path) -> Path:
    """Write ``cube`` as HDF5 (float32 ``reflectance``, float64 ``wavelengths`` in nm), atomically."""
    import h5py

    path = Path(path)
    with atomic_output(path) as (staged,):
        with h5py.File(staged, "w") as handle:
            dataset = handle.create_dataset(CUBE_VARIABLE, data=cube.data,
                                            chunks=(min(64, cube.height), min(64, cube.width),
                                                    cube.bands))
            dataset.attrs["description"] = "reflectance on 0..1, axes (rows, columns, bands)"
            dataset.attrs["source"] = cube.source
            wavelengths = handle.create_dataset(WAVELENGTH_VARIABLE, data=cube.wavelengths)
            wavelengths.attrs["units"] = "nm"
    return path
