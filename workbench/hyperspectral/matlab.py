"""MATLAB ``.mat`` cubes: v5 through :mod:`scipy.io`, v7.3 (HDF5) through h5py.

Variables: ``reflectance`` (H × W × B, as MATLAB's ``size`` shows it) and
``wavelengths`` (1 × B or B × 1, nm); other names are auto-detected
(:mod:`workbench.hyperspectral.variables`). The version is told by the file
itself: a v7.3 file is HDF5 (its axes are stored reversed, which the reader
undoes). :func:`write_cube_mat` writes v5 unless asked for v7.3 or the cube is
too big for v5 (2 GiB a variable); v7.3 files get MATLAB's 512-byte header and
``MATLAB_class`` attributes so that MATLAB's ``load`` reads them.

References
----------
The MathWorks, "MAT-File Format" (Level 5 header: 116-byte text, 8-byte
subsystem offset, version, endian indicator ``IM``); MATLAB ``save -v7.3``
(HDF5 with a 512-byte user block).
"""

from __future__ import annotations

import datetime as _dt
import platform
from pathlib import Path

import numpy as np

from workbench.errors import InputError, SpectrumFileError
from workbench.fileio import atomic_output
from workbench.hyperspectral.cube import ReflectanceCube
from workbench.hyperspectral.hdf5 import read_hdf5_cube
from workbench.hyperspectral.variables import (
    CUBE_VARIABLE,
    WAVELENGTH_VARIABLE,
    pick_cube_variables,
)

__all__ = ["MAT_VERSIONS", "read_cube_mat", "write_cube_mat"]

MAT_VERSIONS = ("auto", "5", "7.3")
"""``write_cube_mat`` versions; ``auto`` is v5 unless the cube exceeds :data:`_V5_LIMIT_BYTES`."""

_V5_LIMIT_BYTES = 2**31 - 1024
_USERBLOCK_BYTES = 512


def _is_hdf5(path: Path) -> bool:
    import h5py

    try:
        return bool(h5py.is_hdf5(path))
    except OSError:
        return False


def read_cube_mat(path) -> ReflectanceCube:
    """Read a MATLAB cube, v5 (scipy) or v7.3 (HDF5), as the file says.

    Raises
    ------
    SpectrumFileError
        Not a readable MAT-file (e.g. truncated), no cube variable, and every
        check of :class:`ReflectanceCube`.
    """
    import scipy.io

    path = Path(path)
    if _is_hdf5(path):
        return read_hdf5_cube(path, matlab_axes=True)
    try:
        variables = scipy.io.loadmat(path, squeeze_me=False, mat_dtype=False)
    except Exception as error:  # scipy raises ValueError, TypeError, MatReadError, ...
        raise SpectrumFileError(path, None, f"not a readable MAT-file ({type(error).__name__}: "
                                f"{error}); it may be truncated",
                                "copy or export the cube again (MATLAB: save -v7 or -v7.3)"
                                ) from None
    arrays = {name: value for name, value in variables.items()
              if not name.startswith("__") and isinstance(value, np.ndarray)
              and value.dtype.kind in "iufb"}
    cube_name, wavelength_name = pick_cube_variables({n: v.shape for n, v in arrays.items()}, path)
    wavelengths = None if wavelength_name is None else arrays[wavelength_name].reshape(-1)
    return ReflectanceCube(arrays[cube_name], wavelengths, str(path))


def _matlab_header() -> bytes:
    created = _dt.datetime.now().strftime("%a %b %d %H:%M:%S %Y")
    text = (f"MATLAB 7.3 MAT-file, Platform: {platform.system()}, Created on: {created} "
            "HDF5 schema 1.00 .").encode("ascii", "replace")[:116].ljust(116, b" ")
    return text + b" " * 8 + b"\x00\x02" + b"IM"


def _write_v73(cube: ReflectanceCube, staged: Path) -> None:
    import h5py

    with h5py.File(staged, "w", userblock_size=_USERBLOCK_BYTES) as handle:
        # MATLAB is column-major: an H×W×B array is stored with HDF5 shape (B, W, H).
        data = handle.create_dataset(CUBE_VARIABLE, data=np.transpose(cube.data))
        data.attrs["MATLAB_class"] = np.bytes_("single")
        wavelengths = handle.create_dataset(WAVELENGTH_VARIABLE,
                                            data=cube.wavelengths.reshape(-1, 1))  # 1×B in MATLAB
        wavelengths.attrs["MATLAB_class"] = np.bytes_("double")
    with open(staged, "r+b") as raw:
        raw.write(_matlab_header())


def write_cube_mat(cube: ReflectanceCube, path, *, version: str = "auto") -> Path:
    """Write ``cube`` as a MAT-file (``reflectance`` single, ``wavelengths`` 1×B double), atomically.

    Parameters
    ----------
    version : {"auto", "5", "7.3"}
        ``auto``: v5 unless the cube is over 2 GiB, then v7.3.
    """
    import scipy.io

    if version not in MAT_VERSIONS:
        raise InputError(f"MAT-file version {version!r}: use one of {', '.join(MAT_VERSIONS)}")
    if version == "auto":
        version = "5" if cube.data.nbytes < _V5_LIMIT_BYTES else "7.3"
    path = Path(path)
    with atomic_output(path) as (staged,):
        if version == "7.3":
            _write_v73(cube, staged)
        else:
            scipy.io.savemat(staged, {CUBE_VARIABLE: cube.data,
                                      WAVELENGTH_VARIABLE: cube.wavelengths.reshape(1, -1)},
                             do_compression=False, format="5")
    return path
