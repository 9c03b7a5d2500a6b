"""Which arrays of a container file (``.npz``, HDF5, MATLAB ``.mat``) are the cube and its wavelengths.

Convention
----------
- The cube is the array named ``reflectance`` (case-insensitive; also accepted,
  in this order: ``reflectances``, ``cube``, ``ref``, ``data``), shape
  ``(H, W, B)`` — rows, columns, bands — as MATLAB and NumPy show it.
- The wavelengths (band centres, nm) are the array named ``wavelengths``
  (also: ``wavelength``, ``bands``, ``wl``, ``lambda``, ``centers``); a row or
  column vector is accepted.
- Without a conventional name, the one 3-D numeric array of the file is the
  cube, and the one vector whose length is the cube's band count gives the
  wavelengths. Several candidates and no conventional name is an error that
  lists them.

Writers in this package always use ``reflectance`` and ``wavelengths``.
"""

from __future__ import annotations

from workbench.errors import SpectrumFileError

__all__ = [
    "CUBE_VARIABLE_NAMES",
    "WAVELENGTH_VARIABLE_NAMES",
    "CUBE_VARIABLE",
    "WAVELENGTH_VARIABLE",
    "pick_cube_variables",
    "vector_length",
]

CUBE_VARIABLE = "reflectance"
WAVELENGTH_VARIABLE = "wavelengths"
CUBE_VARIABLE_NAMES = (CUBE_VARIABLE, "reflectances", "cube", "ref", "data")
WAVELENGTH_VARIABLE_NAMES = (WAVELENGTH_VARIABLE, "wavelength", "bands", "wl", "lambda", "centers")


def vector_length(shape: tuple[int, ...]) -> int | None:
    """The length of a vector stored with ``shape`` ((B,), (1, B), (B, 1)…), else None."""
    long_axes = [n for n in shape if n != 1]
    if len(shape) == 0 or len(long_axes) > 1:
        return None
    return long_axes[0] if long_axes else 1


def _by_convention(shapes: dict[str, tuple[int, ...]], names: tuple[str, ...]) -> str | None:
    lowered = {name.lower(): name for name in shapes}
    for candidate in names:
        if candidate in lowered:
            return lowered[candidate]
    return None


def pick_cube_variables(shapes: dict[str, tuple[int, ...]], path) -> tuple[str, str | None]:
    """Names of the cube array and of the wavelength vector (None if absent).

    Parameters
    ----------
    shapes : dict
        Variable name → shape (as the file presents it, in NumPy axis order),
        numeric arrays only.
    path : path-like
        The file, for error messages.

    Raises
    ------
    SpectrumFileError
        No 3-D array, or several and none named by the convention.
    """
    cube_name = _by_convention(shapes, CUBE_VARIABLE_NAMES)
    if cube_name is not None and len(shapes[cube_name]) != 3:
        raise SpectrumFileError(path, None,
                                f"variable {cube_name!r} has shape {shapes[cube_name]}; a cube is "
                                "3-D (rows, columns, bands)",
                                f"store the reflectance as an (H, W, B) array named {CUBE_VARIABLE!r}")
    if cube_name is None:
        cubes = sorted(name for name, shape in shapes.items() if len(shape) == 3)
        if not cubes:
            found = ", ".join(f"{n} {s}" for n, s in sorted(shapes.items())) or "no numeric arrays"
            raise SpectrumFileError(path, None, f"no 3-D array in the file (found: {found})",
                                    f"store the reflectance as an (H, W, B) array named "
                                    f"{CUBE_VARIABLE!r}")
        if len(cubes) > 1:
            raise SpectrumFileError(path, None,
                                    f"several 3-D arrays ({', '.join(cubes)}) and none is named "
                                    f"{CUBE_VARIABLE!r}",
                                    f"rename the reflectance cube to {CUBE_VARIABLE!r}")
        cube_name = cubes[0]
    bands = shapes[cube_name][2]
    wavelength_name = _by_convention(shapes, WAVELENGTH_VARIABLE_NAMES)
    if wavelength_name is None:
        vectors = sorted(name for name, shape in shapes.items()
                         if name != cube_name and vector_length(shape) == bands and bands > 1)
        if len(vectors) == 1:
            wavelength_name = vectors[0]
    return cube_name, wavelength_name
