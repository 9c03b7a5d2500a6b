"""Cube files: round trips through every format, resampling, and each bad-cube error."""

import os

import h5py
import numpy as np
import pytest
import scipy.io

from workbench.colorimetry import WORKING_WAVELENGTHS
from workbench.errors import SpectrumFileError
from workbench.hyperspectral import (
    CUBE_FORMATS,
    PAPER_CUBE_WAVELENGTHS,
    ReflectanceCube,
    read_cube,
    resample_cube,
    write_cube,
)

WAVELENGTHS = PAPER_CUBE_WAVELENGTHS


@pytest.mark.parametrize("name, options", [
    ("cube.hdr", {}), ("cube.npz", {}), ("cube.h5", {}), ("cube.hdf5", {}),
    ("cube.mat", {}), ("cube.mat", {"version": "5"}), ("cube.mat", {"version": "7.3"}),
])
def test_round_trip_keeps_every_value(tmp_path, random_cube, name, options):
    path = write_cube(random_cube, tmp_path / name, **options)
    back = read_cube(path)
    assert back.shape == random_cube.shape
    assert back.data.dtype == np.float32
    np.testing.assert_array_equal(back.data, random_cube.data)
    np.testing.assert_allclose(back.wavelengths, WAVELENGTHS, rtol=0, atol=1e-9)
    assert back.source == str(path)


def test_every_registered_suffix_round_trips(tmp_path, random_cube):
    for suffix in CUBE_FORMATS:
        back = read_cube(write_cube(random_cube, tmp_path / f"every{suffix}"))
        np.testing.assert_array_equal(back.data, random_cube.data)


def test_writers_leave_only_their_files(tmp_path, random_cube):
    write_cube(random_cube, tmp_path / "a.hdr")
    write_cube(random_cube, tmp_path / "b.mat", version="7.3")
    assert sorted(os.listdir(tmp_path)) == ["a.hdr", "a.img", "b.mat"]


def test_a_failed_write_leaves_the_previous_file_and_no_partial_one(tmp_path, random_cube,
                                                                    monkeypatch):
    import workbench.hyperspectral.npz as npz_module

    target = tmp_path / "cube.npz"
    write_cube(random_cube, target)
    before = target.read_bytes()

    def savez_that_dies(path, **arrays):
        with open(path, "wb") as handle:
            handle.write(b"PK\x03\x04 half an archive")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(npz_module.np, "savez", savez_that_dies)
    with pytest.raises(OSError):
        write_cube(random_cube, target)
    assert target.read_bytes() == before
    assert os.listdir(tmp_path) == ["cube.npz"]


def test_envi_micrometres_and_scale_factor_are_honoured(tmp_path, random_cube):
    import spectral.io.envi as envi

    scaled = np.round(random_cube.data * 10000).astype(np.uint16)
    envi.save_image(str(tmp_path / "int.hdr"), scaled, dtype=np.uint16, interleave="bsq",
                    metadata={"wavelength": [f"{w / 1000:.3f}" for w in WAVELENGTHS],
                              "wavelength units": "Micrometers",
                              "reflectance scale factor": 10000})
    back = read_cube(tmp_path / "int.hdr")
    np.testing.assert_allclose(back.wavelengths, WAVELENGTHS, atol=1e-6)
    np.testing.assert_allclose(back.data, scaled / 10000, atol=1e-6)


def test_mat_v73_is_stored_the_matlab_way(tmp_path, random_cube):
    path = write_cube(random_cube, tmp_path / "matlab.mat", version="7.3")
    assert path.read_bytes()[:19] == b"MATLAB 7.3 MAT-file"
    with h5py.File(path, "r") as handle:
        height, width, bands = random_cube.shape
        assert handle["reflectance"].shape == (bands, width, height)   # column-major
        assert handle["reflectance"].attrs["MATLAB_class"] == b"single"
        assert handle["wavelengths"].shape == (bands, 1)                # 1×B in MATLAB


def test_a_lone_3d_array_and_matching_vector_are_found_by_shape(tmp_path, random_cube):
    path = tmp_path / "scene.mat"
    scipy.io.savemat(path, {"hsi": random_cube.data, "wl_nm": WAVELENGTHS[None, :],
                            "note": np.array([1.0, 2.0])})
    back = read_cube(path)
    np.testing.assert_array_equal(back.data, random_cube.data)
    np.testing.assert_array_equal(back.wavelengths, WAVELENGTHS)


def test_hdf5_wavelengths_may_be_an_attribute(tmp_path, random_cube):
    path = tmp_path / "attr.h5"
    with h5py.File(path, "w") as handle:
        dataset = handle.create_dataset("Cube", data=random_cube.data)
        dataset.attrs["wavelengths"] = WAVELENGTHS
    np.testing.assert_array_equal(read_cube(path).wavelengths, WAVELENGTHS)


def test_resampling_to_the_working_wavelengths(tmp_path, random_cube):
    path = write_cube(random_cube, tmp_path / "c.npz")
    working = read_cube(path, wavelengths=WORKING_WAVELENGTHS)
    assert working.shape == (6, 5, 401)
    texel = random_cube.data[2, 3].astype(float)
    np.testing.assert_allclose(working.data[2, 3], np.interp(WORKING_WAVELENGTHS, WAVELENGTHS, texel),
                               atol=1e-6)
    assert resample_cube(random_cube, WAVELENGTHS) is random_cube


# --- bad cubes --------------------------------------------------------------------------------


def _save_npz(path, **arrays):
    np.savez(path, **arrays)
    return path


def _expect(path, *fragments):
    with pytest.raises(SpectrumFileError) as caught:
        read_cube(path)
    message = str(caught.value)
    assert str(path) in message and "Fix:" in message, message
    for fragment in fragments:
        assert fragment in message, message
    return caught.value


def test_nan_is_refused_with_its_place(tmp_path, random_cube):
    data = random_cube.data.copy()
    data[4, 1, 30] = np.nan
    path = _save_npz(tmp_path / "nan.npz", reflectance=data, wavelengths=WAVELENGTHS)
    _expect(path, "NaN", "row 4, column 1", f"{WAVELENGTHS[30]:g} nm")


def test_reflectance_in_percent_is_refused_with_the_scale_hint(tmp_path, random_cube):
    path = _save_npz(tmp_path / "percent.npz", reflectance=random_cube.data * 100,
                     wavelengths=WAVELENGTHS)
    _expect(path, "outside [0, 1.5]", "percent")


def test_negative_reflectance_is_refused(tmp_path, random_cube):
    data = random_cube.data.copy()
    data[0, 0, 0] = -0.2
    _expect(_save_npz(tmp_path / "neg.npz", reflectance=data, wavelengths=WAVELENGTHS),
            "-0.2", "outside [0, 1.5]")


def test_missing_wavelengths_are_refused(tmp_path, random_cube):
    _expect(_save_npz(tmp_path / "nowl.npz", reflectance=random_cube.data), "no wavelengths")


def test_missing_wavelengths_in_envi_header_are_refused(tmp_path, random_cube):
    import spectral.io.envi as envi

    envi.save_image(str(tmp_path / "nowl.hdr"), random_cube.data, dtype=np.float32)
    _expect(tmp_path / "nowl.hdr", "no wavelengths")


def test_unsorted_wavelengths_are_refused(tmp_path, random_cube):
    shuffled = WAVELENGTHS.copy()
    shuffled[[10, 11]] = shuffled[[11, 10]]
    _expect(_save_npz(tmp_path / "unsorted.npz", reflectance=random_cube.data, wavelengths=shuffled),
            "not strictly increasing", "sort")


def test_a_short_range_is_refused(tmp_path, random_cube):
    _expect(_save_npz(tmp_path / "short.npz", reflectance=random_cube.data,
                      wavelengths=np.linspace(450, 750, WAVELENGTHS.size)),
            "450–750 nm", "400–700 nm")


def test_a_shape_mismatch_is_refused(tmp_path, random_cube):
    _expect(_save_npz(tmp_path / "mismatch.npz", reflectance=random_cube.data,
                      wavelengths=WAVELENGTHS[:-1]),
            "shape mismatch", "101 bands", "100 wavelengths")


def test_a_truncated_envi_data_file_is_refused(tmp_path, random_cube):
    write_cube(random_cube, tmp_path / "cut.hdr")
    data_file = tmp_path / "cut.img"
    data_file.write_bytes(data_file.read_bytes()[:1000])
    error = _expect_truncated(tmp_path / "cut.hdr", data_file)
    assert "truncated" in str(error)


def _expect_truncated(path, named):
    with pytest.raises(SpectrumFileError) as caught:
        read_cube(path)
    assert str(named) in str(caught.value) and "Fix:" in str(caught.value)
    return caught.value


@pytest.mark.parametrize("name, options", [("cut.npz", {}), ("cut.h5", {}), ("cut.mat", {}),
                                           ("cut73.mat", {"version": "7.3"})])
def test_truncated_container_files_are_refused(tmp_path, random_cube, name, options):
    path = write_cube(random_cube, tmp_path / name, **options)
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    error = _expect_truncated(path, path)
    assert "truncated" in str(error)


def test_a_missing_envi_data_file_is_refused(tmp_path, random_cube):
    write_cube(random_cube, tmp_path / "lost.hdr")
    (tmp_path / "lost.img").unlink()
    _expect(tmp_path / "lost.hdr", "data file", "missing")


def test_several_unnamed_3d_arrays_are_refused_by_name(tmp_path, random_cube):
    path = _save_npz(tmp_path / "two.npz", first=random_cube.data, second=random_cube.data,
                     wavelengths=WAVELENGTHS)
    _expect(path, "first", "second", "'reflectance'")


def test_unknown_suffix_and_missing_file(tmp_path):
    with pytest.raises(SpectrumFileError, match=r"\.hdr"):
        read_cube(tmp_path / "cube.tif")
    with pytest.raises(SpectrumFileError, match="give the .hdr header"):
        read_cube(tmp_path / "cube.img")
    with pytest.raises(SpectrumFileError, match="no such file"):
        read_cube(tmp_path / "absent.npz")


def test_the_cube_itself_validates(random_cube):
    with pytest.raises(SpectrumFileError, match="3-D"):
        ReflectanceCube(random_cube.data[0], WAVELENGTHS, "flat")
    with pytest.raises(SpectrumFileError, match="µm"):
        ReflectanceCube(random_cube.data, WAVELENGTHS / 1000, "microns")


@pytest.mark.parametrize("factor, problem", [("ten thousand", "is not a number"),
                                             ("{1, 2}", "is not a number"),
                                             ("0", "is not positive"),
                                             ("-10000", "is not positive")])
def test_a_bad_envi_reflectance_scale_factor_is_named(tmp_path, random_cube, factor, problem):
    import spectral.io.envi as envi

    envi.save_image(str(tmp_path / "scaled.hdr"), random_cube.data, dtype=np.float32,
                    metadata={"wavelength": [f"{w:g}" for w in WAVELENGTHS],
                              "reflectance scale factor": factor})
    _expect(tmp_path / "scaled.hdr", "reflectance scale factor", problem, "10000")


def _hdf5_with_units(path, cube, units, where):
    with h5py.File(path, "w") as handle:
        data = handle.create_dataset("reflectance", data=cube.data)
        wavelengths = handle.create_dataset("wavelengths", data=WAVELENGTHS * (
            1e-3 if units.lower() in ("um", "µm", "micrometers") else 1.0))
        {"wavelengths": wavelengths, "cube": data, "file": handle}[where].attrs[
            "wavelength_units" if where != "wavelengths" else "units"] = units
    return path


@pytest.mark.parametrize("units", ["nm", "nanometers", "Nanometres", "um", "µm", "micrometers"])
@pytest.mark.parametrize("where", ["wavelengths", "cube", "file"])
def test_hdf5_wavelength_units_nm_and_um(tmp_path, random_cube, units, where):
    path = _hdf5_with_units(tmp_path / "units.h5", random_cube, units, where)
    np.testing.assert_allclose(read_cube(path).wavelengths, WAVELENGTHS, rtol=0, atol=1e-9)


@pytest.mark.parametrize("units", ["Angstrom", "cm-1", "GHz", ""])
def test_hdf5_unknown_wavelength_units_are_refused(tmp_path, random_cube, units):
    path = _hdf5_with_units(tmp_path / "units.h5", random_cube, units, "wavelengths")
    _expect(path, f"units = {units}'", "nm", "µm")


def test_hdf5_cube_units_that_are_not_a_length_describe_the_data(tmp_path, random_cube):
    path = tmp_path / "data_units.h5"
    with h5py.File(path, "w") as handle:
        handle.create_dataset("reflectance", data=random_cube.data).attrs["units"] = "1"
        handle.create_dataset("wavelengths", data=WAVELENGTHS)
    np.testing.assert_array_equal(read_cube(path).wavelengths, WAVELENGTHS)
