"""HDF5 cubes (``.h5``/``.hdf5``) through h5py; also the reader under MATLAB v7.3 files.

Layout: top-level datasets ``reflectance`` (H, W, B) and ``wavelengths`` (B,),
nm (names: :mod:`workbench.hyperspectral.variables`; auto-detected otherwise).
The wavelengths may instead be an attribute ``wavelengths`` of the cube
dataset. The wavelengths' unit is the first ``wavelength_units`` or ``units``
attribute of the wavelengths dataset, else of the cube dataset, else of the
file (:data:`WAVELENGTH_UNITS`): ``nm`` (``nanometers``) is taken as is, ``µm``
(``um``, ``micrometers``) is converted to nm, any other name for the
wavelengths is refused, and none means nm (a ``units`` attribute of the cube
or the file that is not a length describes the reflectance data and is passed
over). MATLAB v7.3 files are HDF5 with the axes
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

__all__ = ["WAVELENGTH_UNITS", "read_cube_hdf5", "write_cube_hdf5", "read_hdf5_cube"]

WAVELENGTH_UNITS = {
    **dict.fromkeys(("nm", "nanometer", "nanometers", "nanometre", "nanometres"), 1.0),
    **dict.fromkeys(("µm", "μm", "um", "micrometer", "micrometers", "micrometre", "micrometres",
                     "micron", "microns"), 1000.0),
}
"""Wavelength unit names (lower case) → factor to nm."""


def _units_factor(path, wavelength_attributes, *other_attribute_sets) -> float:
    """Factor to nm from the first units attribute found (module doc).

    On the wavelengths dataset, ``wavelength_units`` and ``units`` name the
    wavelengths' unit; on the cube dataset or the file only
    ``wavelength_units`` does for sure (a ``units`` there that is not a length
    describes the reflectance data and is passed over).
    """
    candidates = []          # (attributes, key, whether it surely names the wavelengths' unit)
    if wavelength_attributes is not None:
        candidates += [(wavelength_attributes, "wavelength_units", True),
                       (wavelength_attributes, "units", True)]
    for attributes in other_attribute_sets:
        candidates += [(attributes, "wavelength_units", True), (attributes, "units", False)]
    for attributes, key, about_wavelengths in candidates:
        if key not in attributes:
            continue
        value = attributes[key]
        if isinstance(value, np.ndarray) and value.size == 1:
            value = value.reshape(()).item()
        value = value.decode(errors="replace") if isinstance(value, bytes) else str(value)
        factor = WAVELENGTH_UNITS.get(value.strip().lower())
        if factor is not None:
            return factor
        if about_wavelengths:
            raise SpectrumFileError(path, None, f"the wavelengths' attribute '{key} = {value}' is "
                                    "not a unit the workbench knows (nm or µm)",
                                    "give the wavelengths in nm (units = 'nm') or in µm "
                                    "(units = 'um')")
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
                factor = _units_factor(path, wavelength_dataset.attrs, cube_dataset.attrs,
                                        handle.attrs)
            else:
                for key in ("wavelengths", "wavelength"):
                    if key in cube_dataset.attrs:
                        wavelengths = np.asarray(cube_dataset.attrs[key], dtype=np.float64).reshape(-1)
                        factor = _units_factor(path, None, cube_dataset.attrs, handle.attrs)
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
