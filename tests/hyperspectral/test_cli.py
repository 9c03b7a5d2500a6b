"""The ``relight`` and ``bench relight`` commands, end to end (small cubes, no timing asserted)."""

import json
import struct
from pathlib import Path

import numpy as np
import pytest

import profiles

from workbench.cli import main
from workbench.colorimetry import WORKING_SHAPE
from workbench.colour_management import engine_render
from workbench.display import SRGBDisplay
from workbench.hyperspectral import (
    PAPER_CUBE_WAVELENGTHS,
    ReflectanceCube,
    authored_srgb8_cube,
    encode_cube,
    fit_cube_basis,
    plan_relight,
    relight_full_band,
    relight_texels,
    write_cube,
)
from workbench.hyperspectral.materials import material_reflectances
from workbench.hyperspectral.png import png_chunks
from workbench.illuminants import get_illuminant


def _png_size(path):
    chunks = dict(png_chunks(path.read_bytes()))
    width, height = struct.unpack(">II", chunks[b"IHDR"][:8])
    return height, width


def _png_rgb8(path):
    from PIL import Image

    with Image.open(path) as image:
        assert image.mode == "RGB"
        return np.asarray(image)


def _within_one(a, b):
    return np.mean(np.abs(a.astype(int) - b.astype(int)).max(axis=-1) <= 1)


@pytest.fixture
def cube_file(tmp_path, small_cube):
    return write_cube(small_cube, tmp_path / "scene.hdr")


@pytest.mark.parametrize("options", [
    ["--level", "2"],
    ["--level", "2", "--basis", "6"],
    ["--level", "2", "--basis", "full"],
    ["--level", "2", "--target", "0.05"],
    ["--level", "1"],
])
def test_relight_writes_the_texture_in_the_cube_layout(tmp_path, cube_file, small_cube, capsys,
                                                       options):
    out = tmp_path / "texture.png"
    status = main(["relight", str(cube_file), "--illuminant", "cie-a", "--display", "srgb",
                   "--out", str(out), "--json", *options])
    assert status == 0
    assert _png_size(out) == (small_cube.height, small_cube.width)
    summary = json.loads(capsys.readouterr().out)
    assert summary["shape"] == list(small_cube.shape)
    assert len(summary["light_rgb8"]) == 3
    if options[-1] == "6":
        assert summary["basis"]["K"] == 6
    # The file holds the texels of design §2, in the cube's layout.
    written = _png_rgb8(out)
    illuminant = get_illuminant("cie-a")
    if options[1] == "1":
        np.testing.assert_array_equal(written, authored_srgb8_cube(small_cube))
        assert "unreachable_texels" not in summary
        return
    full_band = relight_full_band(small_cube, illuminant, SRGBDisplay())
    assert summary["unreachable_texels"] == 0
    if "full" in options:
        np.testing.assert_array_equal(written, full_band)
        return
    # A basis path: exactly what the library's kernel computes for the same basis ...
    components = int(options[-1]) if "--basis" in options else None
    target = float(options[-1]) if "--target" in options else 0.25
    basis = fit_cube_basis(small_cube, components=components, target_max_dE00=target)
    assert summary["basis"]["K"] == basis.components
    np.testing.assert_array_equal(
        written, relight_texels(encode_cube(small_cube, basis), plan_relight(basis, illuminant)))
    # ... and, where the basis is accurate enough for texels (module doc of the basis: one DAC
    # count under CIE A's dim blue is several texel counts), within one count of the full band.
    if "--target" in options:
        assert _within_one(written, full_band) >= 0.99


VIVE_PROFILE = Path(profiles.__file__).parent / "htc-vive-paper.vrprofile.json"


def test_relight_with_a_profile_and_a_render(tmp_path, cube_file, small_cube, capsys):
    out, render = tmp_path / "t.png", tmp_path / "frame.png"
    status = main(["relight", str(cube_file), "--illuminant", "d65-two-peak", "--profile",
                   str(VIVE_PROFILE), "--out", str(out), "--render", str(render), "--json"])
    assert status == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["texture"].startswith("level 2, spectral basis")
    assert _png_size(render) == _png_size(out) == (small_cube.height, small_cube.width)
    texts = dict(payload.split(b"\x00", 1) for kind, payload in png_chunks(out.read_bytes())
                 if kind == b"tEXt")
    light = ",".join(str(v) for v in summary["light_rgb8"]).encode()
    assert texts[b"workbench.light_rgb8"] == light
    # The render is the engine's arithmetic on the written texture under the printed light.
    np.testing.assert_array_equal(_png_rgb8(render),
                                  engine_render(_png_rgb8(out), np.array(summary["light_rgb8"])))


def test_level1_texture_does_not_depend_on_the_source(tmp_path, cube_file):
    import zlib

    pixels = []
    for source in ("cie-a", "cie-fl11"):
        out = tmp_path / f"{source}.png"
        assert main(["relight", str(cube_file), "--illuminant", source, "--display", "srgb",
                     "--level", "1", "--out", str(out)]) == 0
        pixels.append(zlib.decompress(b"".join(payload for kind, payload
                                               in png_chunks(out.read_bytes())
                                               if kind == b"IDAT")))
    assert pixels[0] == pixels[1]


def test_relight_errors_are_one_clear_line(tmp_path, cube_file, capsys):
    status = main(["relight", str(tmp_path / "none.npz"), "--illuminant", "cie-a",
                   "--display", "srgb", "--out", str(tmp_path / "x.png")])
    assert status == 2 and "no such file" in capsys.readouterr().err
    status = main(["relight", str(cube_file), "--illuminant", "cie-a", "--display", "srgb",
                   "--out", str(tmp_path / "x.jpg")])
    assert status == 2 and "*.png" in capsys.readouterr().err
    status = main(["relight", str(cube_file), "--illuminant", "cie-a", "--display", "srgb",
                   "--basis", "many", "--out", str(tmp_path / "x.png")])
    assert status == 2 and "--basis" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_bench_relight_json_has_the_fields(capsys):
    status = main(["bench", "relight", "--size", "32", "--repeats", "2",
                   "--full-band-repeats", "1", "--json"])
    assert status == 0
    result = json.loads(capsys.readouterr().out)
    for field in ("ms_per_relight", "full_band_ms", "speedup_vs_full", "K", "max_dE00",
                  "per_source_max_dE00", "kernel_ms", "plan_ms"):
        assert field in result, field
    assert result["size"] == 32 and result["bands"] == 101
    assert set(result["per_source_max_dE00"]) == {"cie-d65", "cie-a", "cie-fl11", "d65-two-peak"}
    assert result["max_dE00"] == max(result["per_source_max_dE00"].values())
    assert result["ms_per_relight"] > 0 and result["full_band_ms"] > 0
    assert 1 <= result["K"] <= 24 and np.isfinite(result["speedup_vs_full"])
    # Accuracy, not timing: the basis against the full band on materials it never saw.
    assert result["max_dE00"] <= 0.5
    assert result["training_materials"] == "ces99" and result["validation_materials"] == "cie-tcs"
    assert set(result["per_material_set_max_dE00"]) == {"colorchecker", "nist-cqs-vs"}
    assert max(result["per_material_set_max_dE00"].values()) <= result["max_dE00"]
    assert set(result["unreachable_texels"]) == set(result["per_source_max_dE00"])


def test_bench_lists_its_benchmarks(capsys):
    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    assert "relight" in capsys.readouterr().out


def _sample_cube(tmp_path, name, rows, columns):
    """A cube whose texels are the pure samples of one material set (``rows × columns``)."""
    spectra = material_reflectances(name, PAPER_CUBE_WAVELENGTHS)
    data = spectra.reshape(rows, columns, -1).astype(np.float32)
    return write_cube(ReflectanceCube(data, PAPER_CUBE_WAVELENGTHS, name), tmp_path / f"{name}.npz")


@pytest.mark.parametrize("basis", ["auto", "full"])
def test_relight_counts_the_texels_the_light_cannot_carry(tmp_path, capsys, basis):
    import colour

    from workbench.illuminants.files import write_spectrum_csv

    # A narrow 610 nm LED has no blue and little green (sRGB 255, 20, 0): the orange CIE 2017
    # samples need more green than it carries.
    led = write_spectrum_csv(colour.sd_single_led(610, half_spectral_width=15, shape=WORKING_SHAPE),
                             tmp_path / "led610.csv")
    ces = _sample_cube(tmp_path, "ces99", 9, 11)
    assert main(["relight", str(ces), "--illuminant", str(led), "--display", "srgb",
                 "--basis", basis, "--out", str(tmp_path / "led.png"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["light_rgb8"] == [255, 20, 0] and summary["unreachable_texels"] > 0
    # Under D65 the ColorChecker patches are all within the light.
    checker = _sample_cube(tmp_path, "colorchecker", 4, 6)
    assert main(["relight", str(checker), "--illuminant", "cie-d65", "--display", "srgb",
                 "--basis", basis, "--out", str(tmp_path / "d65.png")]) == 0
    assert "unreachable texels: 0 of 24" in capsys.readouterr().out
