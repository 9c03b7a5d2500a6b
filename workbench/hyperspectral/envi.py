"""ENVI cubes (``.hdr`` header + raw data file) through the ``spectral`` package.

Reading takes the band centres from the header's ``wavelength`` field (its
``wavelength units`` may be nm or µm), divides by ``reflectance scale factor``
when the header has one, accepts any interleave (BIP, BIL, BSQ) and any numeric
data type, and checks the data file's size against the header before reading,
so a truncated copy is reported as such. Writing produces float32 BIP data in
``NAME.img`` beside ``NAME.hdr`` (wavelength units ``Nanometers``), atomically.

References
----------
Harris Geospatial, "ENVI Header Files" (header keywords ``samples``, ``lines``,
``bands``, ``interleave``, ``data type``, ``byte order``, ``wavelength``,
``wavelength units``, ``reflectance scale factor``); Boggs, T., Spectral Python
(SPy), ``spectral.io.envi``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from workbench.errors import SpectrumFileError
from workbench.fileio import atomic_output
from workbench.hyperspectral.cube import ReflectanceCube

__all__ = ["read_cube_envi", "write_cube_envi", "ENVI_DATA_SUFFIX"]

ENVI_DATA_SUFFIX = ".img"
"""Suffix of the data file written beside the header."""

_MICROMETRE_UNITS = ("micrometers", "micrometres", "micrometer", "micrometre", "microns",
                     "micron", "um", "µm")


def _wavelengths_nm(header: dict, path) -> np.ndarray | None:
    values = header.get("wavelength")
    if values is None:
        return None
    try:
        wavelengths = np.array([float(v) for v in values])
    except (TypeError, ValueError):
        raise SpectrumFileError(path, None, "the header's 'wavelength' field is not a list of "
                                "numbers", "write the band centres in nm as "
                                "'wavelength = {400.0, 404.0, ...}'") from None
    units = str(header.get("wavelength units", "nanometers")).strip().lower()
    if units in _MICROMETRE_UNITS:
        wavelengths = wavelengths * 1000.0
    elif units not in ("nanometers", "nanometres", "nanometer", "nanometre", "nm", "unknown"):
        raise SpectrumFileError(path, None, f"'wavelength units = {header['wavelength units']}' "
                                "is not a length the workbench knows",
                                "give the band centres in Nanometers or Micrometers")
    return wavelengths


def _reflectance_scale(header: dict, path) -> float:
    """The header's ``reflectance scale factor`` (1 when absent), checked to be a positive number."""
    value = header.get("reflectance scale factor", 1.0)
    fix = ("set 'reflectance scale factor' to the number that means reflectance 1 (e.g. 10000), "
           "or remove it when the data are already on 0..1")
    try:
        scale = float(value)
    except (TypeError, ValueError):
        raise SpectrumFileError(path, None, f"'reflectance scale factor = {value}' is not a number",
                                fix) from None
    if not np.isfinite(scale) or scale <= 0:
        raise SpectrumFileError(path, None, f"'reflectance scale factor = {value}' is not positive",
                                fix)
    return scale


def read_cube_envi(path) -> ReflectanceCube:
    """Read an ENVI cube from its ``.hdr`` header (the data file is found beside it).

    Parameters
    ----------
    path : path-like
        The header file.

    Returns
    -------
    ReflectanceCube
        float32 reflectance (scaled by ``reflectance scale factor``), band
        centres in nm.

    Raises
    ------
    SpectrumFileError
        Unreadable header, missing or truncated data file, missing wavelengths
        and every check of :class:`ReflectanceCube`.
    """
    import spectral.io.envi as envi

    path = Path(path)
    try:
        image = envi.open(str(path))
    except envi.EnviDataFileNotFoundError:
        raise SpectrumFileError(path, None, "the ENVI data file beside the header is missing",
                                f"put the data file next to the header as {path.stem}"
                                f"{ENVI_DATA_SUFFIX} (or .dat/.raw)") from None
    except Exception as error:  # spectral raises many types for a bad header
        try:
            fields = envi.read_envi_header(str(path))
        except Exception:
            fields = {}
        if "reflectance scale factor" in fields:
            _reflectance_scale(fields, path)      # spectral parses it too: name it and its fix
        raise SpectrumFileError(path, None, f"not a readable ENVI header ({error})",
                                "check that this is the .hdr of an ENVI image") from None
    header = image.metadata
    data_file = Path(image.filename)
    expected = image.offset + image.nrows * image.ncols * image.nbands * image.sample_size
    actual = os.path.getsize(data_file)
    if actual < expected:
        raise SpectrumFileError(data_file, None,
                                f"the data file is truncated: {actual} bytes where the header "
                                f"({path.name}: {image.nrows} lines × {image.ncols} samples × "
                                f"{image.nbands} bands) needs {expected}",
                                "copy or export the cube again (the transfer stopped early)")
    wavelengths = _wavelengths_nm(header, path)
    try:
        raw = image.open_memmap(interleave="bip", writable=False)
    except Exception as error:
        raise SpectrumFileError(data_file, None, f"the data cannot be mapped ({error})",
                                "export the cube again as uncompressed ENVI") from None
    data = np.array(raw, dtype=np.float32)
    del raw
    scale = _reflectance_scale(header, path)
    if scale != 1.0:
        data /= np.float32(scale)
    return ReflectanceCube(data, wavelengths, str(path))


def write_cube_envi(cube: ReflectanceCube, path) -> Path:
    """Write ``cube`` as ``path`` (``.hdr``) + ``.img`` (float32, BIP), atomically.

    Returns
    -------
    Path
        The header's path.
    """
    import spectral.io.envi as envi

    path = Path(path)
    data_path = path.with_suffix(ENVI_DATA_SUFFIX)
    metadata = {
        "description": f"reflectance cube (0..1) from {cube.source}",
        "wavelength": [f"{w:.6g}" for w in cube.wavelengths],
        "wavelength units": "Nanometers",
    }
    with atomic_output(data_path, path) as (_, staged_header):
        envi.save_image(str(staged_header), cube.data, dtype=np.float32, interleave="bip",
                        ext=ENVI_DATA_SUFFIX, force=True, metadata=metadata)
    return path
