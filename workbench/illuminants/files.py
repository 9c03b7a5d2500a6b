"""Light sources from and to files: CSV (``wavelength,value``) and IES TM-27 XML.

Validation (both formats) names the file, the line where it can, the problem
and the fix: non-numeric values, NaN, negative power, unsorted or duplicate
wavelengths, and a range too narrow for colorimetry (it must cover
:data:`REQUIRED_RANGE_NM`; the working range 380–780 nm is filled by holding
the end values, which the import description states).

TM-27 reading and writing is colour-science's
(:class:`colour.io.SpectralDistribution_IESTM2714`).
"""

from __future__ import annotations

import csv
import math
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import colour
import numpy as np

from workbench.colorimetry import WORKING_SHAPE, as_spectral_distribution
from workbench.errors import SpectrumFileError
from workbench.fileio import atomic_output, atomic_writer
from workbench.illuminants.source import Illuminant

__all__ = [
    "REQUIRED_RANGE_NM",
    "read_spectrum_csv",
    "write_spectrum_csv",
    "read_spectrum_tm27",
    "write_spectrum_tm27",
    "read_illuminant_file",
    "write_illuminant_file",
    "SPECTRUM_READERS",
]

REQUIRED_RANGE_NM = (400.0, 700.0)
"""A source file must cover at least this range (nm)."""


def _check_series(path, wavelengths: np.ndarray, values: np.ndarray, lines: list[int | None]) -> None:
    if len(wavelengths) < 2:
        raise SpectrumFileError(path, None, f"only {len(wavelengths)} data point(s)",
                                "give the spectrum at many wavelengths (e.g. every 1–5 nm)")
    for i in range(1, len(wavelengths)):
        if wavelengths[i] == wavelengths[i - 1]:
            raise SpectrumFileError(path, lines[i], f"wavelength {wavelengths[i]:g} nm appears twice",
                                    "keep one value per wavelength")
        if wavelengths[i] < wavelengths[i - 1]:
            raise SpectrumFileError(
                path, lines[i],
                f"wavelength {wavelengths[i]:g} nm comes after {wavelengths[i - 1]:g} nm",
                "sort the rows by increasing wavelength")
    for i, value in enumerate(values):
        if not math.isfinite(value):
            raise SpectrumFileError(path, lines[i], f"the value at {wavelengths[i]:g} nm is {value}",
                                    "replace it with a measured number")
        if value < 0:
            raise SpectrumFileError(path, lines[i],
                                    f"negative power {value:g} at {wavelengths[i]:g} nm",
                                    "spectral power cannot be negative; clip noise at 0 "
                                    "or subtract the dark reading correctly")
    low, high = REQUIRED_RANGE_NM
    if wavelengths[0] > low or wavelengths[-1] < high:
        raise SpectrumFileError(
            path, None,
            f"the spectrum covers {wavelengths[0]:g}–{wavelengths[-1]:g} nm, too narrow",
            f"give values over at least {low:g}–{high:g} nm (ideally 380–780 nm)")
    if not np.any(values > 0):
        raise SpectrumFileError(path, None, "every value is zero", "a light source must emit light")


def read_spectrum_csv(path) -> colour.SpectralDistribution:
    """Read ``wavelength,value`` rows (an optional header row, ``#`` comments)."""
    path = Path(path)
    if not path.is_file():
        raise SpectrumFileError(path, None, "no such file", "check the path")
    wavelengths, values, lines = [], [], []
    with path.open(newline="", encoding="utf-8-sig") as handle:
        for line, row in enumerate(csv.reader(handle), start=1):
            cells = [cell.strip() for cell in row]
            if not cells or not any(cells) or cells[0].startswith("#"):
                continue
            if len(cells) < 2:
                raise SpectrumFileError(path, line, f"one field ({cells[0]!r}) where two are needed",
                                        "write each row as wavelength,value")
            try:
                wavelength, value = float(cells[0]), float(cells[1])
            except ValueError:
                if not wavelengths and not lines:
                    lines.append(None)  # header row
                    continue
                raise SpectrumFileError(path, line, f"{cells[0]!r},{cells[1]!r} is not numeric",
                                        "write plain numbers: wavelength in nm, then the value"
                                        ) from None
            wavelengths.append(wavelength)
            values.append(value)
            lines.append(line)
    lines = [line for line in lines if line is not None]
    if not wavelengths:
        raise SpectrumFileError(path, None, "no data rows", "write one wavelength,value row per line")
    wavelengths, values = np.array(wavelengths), np.array(values)
    _check_series(path, wavelengths, values, lines)
    return colour.SpectralDistribution(values, wavelengths, name=path.stem)




def write_spectrum_csv(sd: colour.SpectralDistribution, path) -> Path:
    """Write ``wavelength,value`` rows with a header, atomically."""
    with atomic_writer(path, newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["wavelength", "value"])
        for wavelength, value in zip(sd.wavelengths, sd.values):
            writer.writerow([f"{wavelength:g}", f"{value:.8g}"])
    return Path(path)


def read_spectrum_tm27(path) -> colour.SpectralDistribution:
    """Read an IES TM-27 (TM-2714) XML spectral document."""
    path = Path(path)
    if not path.is_file():
        raise SpectrumFileError(path, None, "no such file", "check the path")
    try:
        sd = colour.io.SpectralDistribution_IESTM2714(str(path)).read()
    except ElementTree.ParseError as error:
        line = error.position[0] if getattr(error, "position", None) else None
        raise SpectrumFileError(path, line, f"not well-formed XML ({error})",
                                "export the file again as IES TM-27 XML") from None
    except (ValueError, TypeError, KeyError, AttributeError) as error:
        raise SpectrumFileError(path, None, f"not a TM-27 spectral document ({error})",
                                "the XML needs <SpectralDistribution> with <SpectralData "
                                "wavelength=...> elements") from None
    if sd is None or len(sd.wavelengths) == 0:
        raise SpectrumFileError(path, None, "no <SpectralData> elements",
                                "the XML needs <SpectralData wavelength=...> elements")
    order = np.argsort(sd.wavelengths, kind="stable")
    _check_series(path, np.asarray(sd.wavelengths)[order], np.asarray(sd.values)[order],
                  [None] * len(order))
    name = (sd.header.description or path.stem) if sd.header else path.stem
    return colour.SpectralDistribution(np.asarray(sd.values)[order],
                                       np.asarray(sd.wavelengths)[order], name=name)


def write_spectrum_tm27(sd: colour.SpectralDistribution, path, *, description: str = "",
                        creator: str = "vr-colour-workbench") -> Path:
    """Write an IES TM-27 XML document (relative spectral power), atomically."""
    header = colour.io.Header_IESTM2714(
        manufacturer="", catalog_number="", description=description or sd.name,
        document_creator=creator, unique_identifier="", measurement_equipment="",
        laboratory="", report_number="", report_date="", document_creation_date="",
        comments="written by the VR colour workbench")

    document = colour.io.SpectralDistribution_IESTM2714(
        header=header, spectral_quantity="relative",
        reflection_geometry="other", transmission_geometry="other",
        bandwidth_FWHM=float(np.min(np.diff(sd.wavelengths))), bandwidth_corrected=False,
        data=np.asarray(sd.values), domain=np.asarray(sd.wavelengths))
    with atomic_output(path) as (staged,):  # colour-science writes by path
        document.path = str(staged)  # set after construction: a path given to it is read at once
        document.write()
    return Path(path)


SPECTRUM_READERS = {".csv": read_spectrum_csv, ".xml": read_spectrum_tm27}
_WRITERS = {".csv": write_spectrum_csv, ".xml": write_spectrum_tm27}


def _suffix(path: Path, table: dict) -> str:
    suffix = path.suffix.lower()
    if suffix not in table:
        raise SpectrumFileError(path, None, f"unknown spectrum file type {suffix!r}",
                                f"use one of {sorted(table)} (CSV wavelength,value or IES TM-27 XML)")
    return suffix


def read_illuminant_file(path) -> Illuminant:
    """A light source from a CSV or TM-27 file, resampled to the working range."""
    path = Path(path)
    raw = SPECTRUM_READERS[_suffix(path, SPECTRUM_READERS)](path)
    note = ""
    if raw.wavelengths[0] > WORKING_SHAPE.start or raw.wavelengths[-1] < WORKING_SHAPE.end:
        note = (f"; measured {raw.wavelengths[0]:g}–{raw.wavelengths[-1]:g} nm, "
                "end values held to 380–780 nm")
    return Illuminant(id=f"file:{path}", name=raw.name or path.stem, kind="imported",
                      sd=as_spectral_distribution(raw, name=raw.name or path.stem),
                      description=f"imported from {path}{note}", native_sd=raw)


def write_illuminant_file(illuminant: Illuminant, path) -> Path:
    """Write a source as CSV or TM-27 XML, chosen by the file suffix."""
    path = Path(path)
    writer = _WRITERS[_suffix(path, _WRITERS)]
    if writer is write_spectrum_tm27:
        return writer(illuminant.sd, path, description=illuminant.name)
    return writer(illuminant.sd, path)
