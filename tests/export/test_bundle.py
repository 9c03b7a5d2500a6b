"""The bundle's files, the .cube convention and accuracy, the export and predict --inverse commands."""

import io
import json
import sys

import numpy as np
import pytest

from tests.export.conftest import BUNDLE_LIGHTS
from workbench.errors import InputError, WorkbenchError
from workbench.export import (
    RUNTIME_FILES,
    cube_accuracy,
    display_inverse_table,
    read_cube_file,
    srgb_input_to_XYZ,
    white_mapping_XYZ,
    write_bundle,
)
from workbench.profile import RUNTIME_COLOUR_SPACE, load_profile


def test_bundle_holds_every_file_and_a_profile_that_records_the_contracts(simulated_bundle):
    bundle, summary = simulated_bundle
    manifest = json.loads((bundle / "bundle.json").read_text())
    assert manifest["format_version"] == 1 and manifest["lights"] == list(BUNDLE_LIGHTS)
    for name in ("profile.vrprofile.json", "display_inverse.cube", "display_inverse.json",
                 "display_drive_correction.bin", "lights.json", "README.md"):
        assert (bundle / name).is_file(), name
    for name in RUNTIME_FILES:
        assert (bundle / "runtime" / name).is_file(), name
    for name in ("coefficients.bin", "coefficients.json", "basis.json", "lights.json",
                 "preview.png"):
        assert (bundle / "level2" / "paint" / name).is_file(), name
    profile = load_profile(bundle / "profile.vrprofile.json")   # validates against the schema
    assert profile.lut3d["file"] == "display_inverse.cube" and profile.lut3d["size"] == 33
    assert profile.lut3d["direction"] == "sRGB_to_DAC"
    np.testing.assert_allclose(profile.lut3d["white_mapping"]["XYZ"],
                               white_mapping_XYZ(profile.display_model(), profile.k))
    assert profile.lut3d["accuracy"]["mean_dE00"] == round(summary.cube_accuracy.mean_dE00, 4)
    assert profile.runtime["colour_space"] == RUNTIME_COLOUR_SPACE
    assert [light["id"] for light in profile.lights] == list(BUNDLE_LIGHTS)
    assert summary.drive_correction  # channel interaction: the drive is not affine in XYZ
    inverse = json.loads((bundle / "display_inverse.json").read_text())["accuracy"]
    assert inverse["identical_share"] == round(summary.inverse_accuracy.identical, 5) >= 0.99
    assert inverse["max_counts"] <= 1


def test_lights_json_is_the_level1_table(simulated_bundle, simulated_profile):
    from workbench.display import srgb_decode

    bundle, _ = simulated_bundle
    table = json.loads((bundle / "lights.json").read_text())
    for light in table["lights"]:
        assert set(light) >= {"id", "name", "rgb8", "linear", "XYZ", "Rf", "CCT"}
        np.testing.assert_allclose(light["linear"], srgb_decode(np.array(light["rgb8"]) / 255),
                                   atol=1e-8)
        assert light["XYZ"][1] == pytest.approx(
            simulated_profile.k * simulated_profile.display_model().white_XYZ[1], rel=1e-6)
    # level 2 assumes the same engine light colour as level 1
    level2 = json.loads((bundle / "level2" / "paint" / "lights.json").read_text())["lights"]
    assert [light["light_rgb8"] for light in level2] == [light["rgb8"] for light in table["lights"]]


def test_coefficient_file_is_ceil_c_over_4_rgba_half_layers(simulated_bundle):
    bundle, summary = simulated_bundle
    header = json.loads((bundle / "level2" / "paint" / "coefficients.json").read_text())
    entry = summary.cubes[0]
    assert header["channels"] == entry["components"] + entry["split"]
    assert header["layers"] == -(-header["channels"] // 4)
    size = (bundle / "level2" / "paint" / "coefficients.bin").stat().st_size
    assert size == header["bytes"] == header["layers"] * header["height"] * header["width"] * 8
    choice = entry["choice"]
    assert choice["meets_target"]
    assert min(choice["identical_share"].values()) >= 0.99


def test_bundle_readme_says_how_to_load_it_in_unity(simulated_bundle):
    bundle, _ = simulated_bundle
    text = (bundle / "README.md").read_text()
    assert "VrColourBundle.Load(" in text and "bundle.LightColour(" in text
    assert "bundle.Relight(" in text and "XR_COLOR_SPACE_UNMANAGED_FB" in text
    assert "$" not in text.replace("$$", "")   # every template field filled


def test_cube_file_follows_the_unity_resolve_convention(vive_bundle, vive_profile):
    bundle, _ = vive_bundle
    lines = (bundle / "display_inverse.cube").read_text().splitlines()
    assert lines[0].startswith("TITLE ")
    assert not any(line.startswith("DOMAIN_") for line in lines)
    assert "LUT_3D_SIZE 33" in lines
    rows = [line for line in lines if line[:1].isdigit()]
    assert len(rows) == 33 ** 3
    values = np.array([[float(v) for v in row.split()] for row in rows])
    assert values.min() >= 0 and values.max() <= 1
    # red fastest: the second row is (1/32, 0, 0) of the input cube
    display = vive_profile.display_model()
    second = display.inverse(srgb_input_to_XYZ([1 / 32, 0, 0], display, vive_profile.k)) / 255
    np.testing.assert_allclose(values[1], second, atol=1e-6)
    thirty_fourth = display.inverse(srgb_input_to_XYZ([0, 1 / 32, 0], display,
                                                      vive_profile.k)) / 255
    np.testing.assert_allclose(values[33], thirty_fourth, atol=1e-6)


@pytest.mark.parametrize("which", ["simulated", "vive"])
def test_cube_sampled_trilinearly_is_within_half_a_delta_e_of_the_exact_inverse(request, which):
    profile = request.getfixturevalue(f"{which}_profile")
    bundle, _ = request.getfixturevalue(f"{which}_bundle")
    table = read_cube_file(bundle / "display_inverse.cube")
    accuracy = cube_accuracy(table, profile.display_model(), profile.k)
    assert accuracy.samples > 10000
    assert accuracy.mean_dE00 <= 0.5
    assert accuracy.p95_dE00 <= 0.1
    # a coarse table is measurably worse: the measure can fail
    coarse = cube_accuracy(display_inverse_table(profile.display_model(), profile.k, 3),
                           profile.display_model(), profile.k)
    assert coarse.mean_dE00 > 2 * accuracy.mean_dE00


def test_cube_node_equals_predict_inverse(vive_bundle, vive_profile, monkeypatch, capsys):
    from workbench.cli import main

    bundle, _ = vive_bundle
    table = read_cube_file(bundle / "display_inverse.cube")
    display = vive_profile.display_model()
    nodes = np.array([[16, 8, 4], [32, 32, 32], [5, 20, 11]])
    XYZ = srgb_input_to_XYZ(nodes / 32.0, display, vive_profile.k)
    monkeypatch.setattr(sys, "stdin", io.StringIO("X,Y,Z\n" + "\n".join(
        ",".join(f"{v:.12g}" for v in row) for row in XYZ)))
    assert main(["predict", str(bundle / "profile.vrprofile.json"), "--inverse"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "r,g,b"
    dac = np.array([[float(v) for v in line.split(",")] for line in out[1:]])
    expected = table[nodes[:, 2], nodes[:, 1], nodes[:, 0]] * 255
    np.testing.assert_allclose(dac, expected, atol=1e-3)


def test_predict_inverse_refuses_bad_rows(vive_bundle, monkeypatch, capsys):
    from workbench.cli import main

    bundle, _ = vive_bundle
    monkeypatch.setattr(sys, "stdin", io.StringIO("X,Y,Z\n1,2\n"))
    assert main(["predict", str(bundle / "profile.vrprofile.json"), "--inverse"]) == 2
    assert "need 3 values X,Y,Z" in capsys.readouterr().err
    monkeypatch.setattr(sys, "stdin", io.StringIO("inf,1,1\n"))
    assert main(["predict", str(bundle / "profile.vrprofile.json"), "--inverse"]) == 2
    assert "NaN or infinity" in capsys.readouterr().err


def test_export_command_writes_a_bundle_from_cube_files(tmp_path, vive_profile, capsys):
    from profiles import example_profile_path
    from workbench.cli import main
    from workbench.hyperspectral import synthesize_cube, write_cube

    cube = tmp_path / "tiles.npz"
    write_cube(synthesize_cube(24, 20, cell=6, seed=2), cube)
    out = tmp_path / "bundle"
    status = main(["export", str(example_profile_path("htc-vive-paper")), "--bundle", str(out),
                   "--lights", "cie-d65,cie-a", "--cube", str(cube), "--lut-size", "17", "--json"])
    assert status == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["lights"] == ["cie-d65", "cie-a"]
    assert summary["display_inverse_cube"]["size"] == 17
    assert summary["cubes"][0]["name"] == "tiles" and not summary["drive_correction"]
    assert (out / "level2" / "tiles" / "coefficients.bin").is_file()
    assert not list(tmp_path.glob(".bundle.*"))          # no staging folder left behind
    # an export again replaces the bundle whole
    assert main(["export", str(example_profile_path("htc-vive-paper")), "--bundle", str(out),
                 "--lights", "cie-d65"]) == 0
    assert not (out / "level2").exists()
    assert json.loads((out / "bundle.json").read_text())["lights"] == ["cie-d65"]


@pytest.mark.slow
def test_export_lightbooth_adds_the_unity_sample_s_two_cubes(tmp_path, capsys):
    from profiles import example_profile_path
    from workbench.cli import main

    out = tmp_path / "bundle"
    assert main(["export", str(example_profile_path("htc-vive-paper")), "--bundle", str(out),
                 "--lights", "cie-d65", "--lut-size", "9", "--lightbooth", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert [cube["name"] for cube in summary["cubes"]] == ["colorchecker", "ishihara"]
    for name in ("colorchecker", "ishihara"):
        assert (out / "level2" / name / "coefficients.bin").is_file()


def test_export_refuses_a_folder_that_is_not_a_bundle(tmp_path, vive_profile):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="holds files and is not a bundle"):
        write_bundle(vive_profile, tmp_path, light_ids=["cie-d65"])
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_export_errors_name_the_input(tmp_path, vive_profile):
    with pytest.raises(InputError, match="2..129"):
        write_bundle(vive_profile, tmp_path / "b", light_ids=["cie-d65"], lut_size=1)
    with pytest.raises(WorkbenchError, match="no-such-light"):
        write_bundle(vive_profile, tmp_path / "b", light_ids=["no-such-light"])
    with pytest.raises(InputError, match="light cie-a named more than once"):
        write_bundle(vive_profile, tmp_path / "b", light_ids=["cie-a", "cie-d65", "cie-a"])
    assert not (tmp_path / "b").exists()
    (tmp_path / "a-file").write_text("mine")
    with pytest.raises(InputError, match="cannot create a folder"):
        write_bundle(vive_profile, tmp_path / "a-file" / "b", light_ids=["cie-d65"])


@pytest.mark.slow
def test_a_fresh_simulated_calibration_bundles_and_conforms(tmp_path):
    """simulate → diagnose → profile → bundle → reference consumer, with whatever model the
    diagnosis gives today (acceptance: a bundle from a simulated calibration with an effect)."""
    import subprocess

    from workbench.cli.diagnose import export_profile
    from workbench.colour_management import light_colour
    from workbench.diagnostics import diagnose
    from workbench.hyperspectral import relight_level2_full_band, synthesize_cube
    from workbench.illuminants import get_illuminant
    from workbench.simulated_sessions import simulate_session

    diagnosis = diagnose(simulate_session({"channel-interaction": 0.08, "black-offset": 0.005},
                                          seed=4))
    profile = load_profile(export_profile(diagnosis, tmp_path / "fresh.vrprofile.json"))
    assert profile.display_model().model_id != "gamma-matrix"
    cube = synthesize_cube(32, 24, cell=8, seed=3)
    summary = write_bundle(profile, tmp_path / "bundle", light_ids=["cie-d65", "cie-a"],
                           cubes=[("tiles", cube)])
    script = tmp_path / "bundle" / "runtime" / "reference_consumer.py"
    for light_id in ("cie-d65", "cie-a"):
        result = subprocess.run([sys.executable, "-I", str(script), str(tmp_path / "bundle"),
                                 "light", light_id], capture_output=True, text=True, timeout=60)
        expected = light_colour(get_illuminant(light_id).sd, profile.display_model(), k=profile.k)
        assert json.loads(result.stdout)["rgb8"] == [int(v) for v in expected.rgb8]
        png = tmp_path / f"{light_id}.png"
        result = subprocess.run([sys.executable, "-I", str(script), str(tmp_path / "bundle"),
                                 "texture", "tiles", "--light", light_id, "--out", str(png)],
                                capture_output=True, text=True, timeout=60)
        assert result.returncode == 0, result.stderr
        from PIL import Image

        texels = np.asarray(Image.open(png).convert("RGB"))
        reference = relight_level2_full_band(cube, get_illuminant(light_id),
                                             profile.display_model(), k=profile.k).texels
        assert np.mean(np.all(texels == reference, axis=-1)) >= 0.99
    assert summary.cube_accuracy.mean_dE00 <= 0.5


@pytest.mark.parametrize("text, message", [
    ("LUT_3D_SIZE x\n", "line 1: 'LUT_3D_SIZE x' is not a size"),
    ("LUT_3D_SIZE 2\n" + "0 0 0\n" * 7 + "0 0 -\n", "line 9: .* is not a size or a row"),
    ("LUT_3D_SIZE 2\n" + "0 0\n" * 8, "N³ rows"),
    ("DOMAIN_MIN 0 0 0\n", "unsupported keyword 'DOMAIN_MIN'"),
])
def test_a_malformed_cube_file_is_an_input_error_naming_the_line(tmp_path, text, message):
    path = tmp_path / "bad.cube"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_cube_file(path)


def test_a_failed_export_leaves_the_earlier_bundle_whole(tmp_path, vive_profile, monkeypatch):
    import workbench.export.bundle as bundle_module

    out = tmp_path / "bundle"
    write_bundle(vive_profile, out, light_ids=["cie-d65"], lut_size=5)
    before = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}

    def fail(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(bundle_module, "lights_table", fail)           # inside the staging block
    with pytest.raises(OSError, match="disk full"):
        write_bundle(vive_profile, out, light_ids=["cie-a"], lut_size=5)
    monkeypatch.undo()
    real_replace = bundle_module.os.replace

    def replace(source, target):                                       # the swap itself fails
        if str(source).endswith(".partial"):
            raise OSError("disk full")
        real_replace(source, target)

    monkeypatch.setattr(bundle_module.os, "replace", replace)
    with pytest.raises(OSError, match="disk full"):
        write_bundle(vive_profile, out, light_ids=["cie-a"], lut_size=5)
    assert {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["bundle"]          # nothing left beside it


def test_export_command_says_when_a_cube_misses_its_target(tmp_path, vive_profile, monkeypatch,
                                                           capsys):
    import functools

    import workbench.export
    from profiles import example_profile_path
    from workbench.cli import main
    from workbench.hyperspectral import synthesize_cube, write_cube

    cube = tmp_path / "tiles.npz"
    write_cube(synthesize_cube(24, 20, cell=6, seed=2), cube)
    # a share no basis reaches: the choice misses its target and the command says so
    monkeypatch.setattr(workbench.export, "write_bundle",
                        functools.partial(workbench.export.write_bundle, target_share=1.01))
    assert main(["export", str(example_profile_path("htc-vive-paper")), "--bundle",
                 str(tmp_path / "b"), "--lights", "cie-d65", "--cube", str(cube),
                 "--lut-size", "5"]) == 0
    out = capsys.readouterr().out
    assert "[below target: " in out and "(target 101.0 %)" in out, out


def test_coefficients_beyond_float16_are_refused_not_written_as_infinity(tmp_path, paint_cube):
    from dataclasses import replace

    from workbench.export.level2_files import write_level2_cube
    from workbench.hyperspectral import fit_cube_basis

    basis = fit_cube_basis(paint_cube, observer="cie1931-2", k=1.0)
    huge = replace(basis, projection=basis.projection * 1e7)
    with pytest.raises(InputError, match="exceed the float16 range"):
        write_level2_cube(tmp_path, "paint", paint_cube, huge, 0, [], None)
    assert not (tmp_path / "level2" / "paint" / "coefficients.bin").exists()
