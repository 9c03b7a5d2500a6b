"""The Unity package: its layout, its place in every bundle, and the loader's numbers executed.

The package's C# (VrColourBundle, VrCubeLut, VrLevel2Cpu and the components VrBundleLight,
VrLevel2Material, VrDisplayInverse) is compiled with mcs against the UnityEngine test double
(tests/export/unity_stub/UnityEngine.cs) and run under mono by tests/export/unity_mono/
LoaderDriver.cs on bundles written by ``export``; every number it gives a scene is compared
with the bundle's reference consumer (runtime/reference_consumer.py).

Exactness. Whatever both sides compute with the same float32 operations in the same order is
compared bit for bit (light colours, the .cube table and its trilinear samples, the display
inverse's tables, the pre-pass, the level-2 arithmetic after the drive). Two things are not:
the level-2 drive (a sum of C products: numpy's float32 matrix product leaves the order to
BLAS, the C# sums in channel order), held to the float32 summation bound 2·C·ε·Σ|p·m| per
texel, after which each side's texel follows from its own drive exactly; and the Texture3D
sampled at GPU texel centres, held to 1e-5 (module doc of test below).
"""

import base64
import json
import shutil
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

import workbench
from tests.export.conftest import BUNDLE_LIGHTS
from tests.export.test_conformance import consumer_module
from tests.export.tools import need_tool
from workbench.export import runtime_file
from workbench.export.bundle import UNITY_PACKAGE, unity_package_files

HERE = Path(__file__).parent
STUB = HERE / "unity_stub" / "UnityEngine.cs"
DRIVER = HERE / "unity_mono" / "LoaderDriver.cs"
PACKAGE = Path(workbench.__file__).parent / "export" / "runtime" / UNITY_PACKAGE
LOADER_SOURCES = ("VrColourBundle.cs", "VrCubeLut.cs", "VrLevel2Cpu.cs", "VrBundleLight.cs",
                  "VrLevel2Material.cs", "VrDisplayInverse.cs")
MCS = ["-langversion:7.2", "-warnaserror+"]
EPS32 = float(np.finfo(np.float32).eps) / 2     # unit roundoff of float32, 2^-24


def need_mono() -> str:
    path = shutil.which("mono")
    if path is None:
        pytest.skip("mono not found: install the Debian package mono-runtime (make test installs it "
                    "as root)")
    return path


def _mcs(*arguments) -> None:
    result = subprocess.run([need_tool("mcs"), *MCS, *map(str, arguments)], capture_output=True,
                            text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr


@pytest.fixture(scope="module")
def engine(tmp_path_factory) -> Path:
    """The UnityEngine test double as UnityEngine.dll."""
    out = tmp_path_factory.mktemp("unity") / "UnityEngine.dll"
    _mcs("-target:library", f"-out:{out}", STUB)
    return out


@pytest.fixture(scope="module")
def driver(engine) -> Path:
    """LoaderDriver.exe over the package's loader and components (as their own assembly)."""
    need_mono()
    runtime = engine.parent / "VrColourWorkbench.Runtime.dll"
    _mcs("-target:library", f"-r:{engine}", f"-out:{runtime}",
         *(runtime_file(f"unity/Runtime/{name}") for name in LOADER_SOURCES))
    exe = engine.parent / "LoaderDriver.exe"
    _mcs(f"-r:{engine}", f"-r:{runtime}", f"-out:{exe}", DRIVER)
    return exe


def cube_points() -> np.ndarray:
    """Where the .cube is sampled: nodes, cell midpoints, edges, beyond 0..1, and random colours."""
    rng = np.random.default_rng(16)
    grid = np.linspace(0.0, 1.0, 9)
    nodes = np.stack(np.meshgrid(grid, grid, grid, indexing="ij"), -1).reshape(-1, 3)
    special = np.array([[0, 0, 0], [1, 1, 1], [1 / 64, 0.5, 1 - 1 / 64], [0.999999, 0.5, 0.25],
                        [-0.2, 0.5, 1.3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0],
                        [0.5, 0.5, 0.5], [15.5 / 32, 16.5 / 32, 31.5 / 32]])
    return np.vstack([nodes, special, rng.random((2000, 3)),
                      rng.integers(0, 256, (500, 3)) / 255.0]).astype(np.float32)


def authored_pixels() -> np.ndarray:
    """A 64 × 64 sRGB-authored RGBA texture: every grey level, the primaries' ramps, random colours."""
    rng = np.random.default_rng(61)
    pixels = rng.integers(0, 256, (64 * 64, 4), dtype=np.uint8)
    ramp = np.arange(256, dtype=np.uint8)
    pixels[:256, :3] = ramp[:, None]
    for channel in range(3):
        pixels[256 * (channel + 1):256 * (channel + 2), :3] = 0
        pixels[256 * (channel + 1):256 * (channel + 2), channel] = ramp
    return pixels


_RUNS: dict = {}


def run_driver(driver: Path, bundle: Path, tmp_path: Path, cube: str = "paint"):
    points, pixels = tmp_path / "points.f32", tmp_path / "pixels.rgba"
    cube_points().astype("<f4").tofile(points)
    authored_pixels().tofile(pixels)
    return subprocess.run(["mono", str(driver), str(bundle), str(points), str(pixels), cube],
                          capture_output=True, text=True, timeout=300)


@pytest.fixture(params=["simulated_bundle", "vive_bundle"])
def loaded(request, driver, tmp_path_factory):
    """(bundle folder, the driver's JSON, the reference consumer module), once per bundle."""
    bundle, _ = request.getfixturevalue(request.param)
    if bundle not in _RUNS:
        result = run_driver(driver, bundle, tmp_path_factory.mktemp("driver"))
        assert result.returncode == 0, result.stderr
        _RUNS[bundle] = json.loads(result.stdout)
    return bundle, _RUNS[bundle], consumer_module(bundle)


def f32(text: str) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), dtype="<f4")


def u8(text: str) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), dtype=np.uint8)


def assert_bits_equal(actual: np.ndarray, expected: np.ndarray, what: str) -> None:
    actual = np.asarray(actual, dtype=np.float32).reshape(-1)
    expected = np.asarray(expected, dtype=np.float32).reshape(-1)
    assert actual.shape == expected.shape, what
    different = actual.view(np.uint32) != expected.view(np.uint32)
    assert not different.any(), (f"{what}: {int(different.sum())} of {different.size} differ, "
                                 f"largest by {np.abs(actual - expected).max()}")


# the package ---------------------------------------------------------------------------------

def test_package_manifest_is_a_unity_package_of_this_workbench_version():
    manifest = json.loads((PACKAGE / "package.json").read_text())
    assert manifest["name"] == "org.vrcolourworkbench.runtime"
    assert manifest["version"] == workbench.__version__
    assert manifest["unity"] == "2021.3" and manifest["license"] == "MIT"
    samples = {sample["displayName"]: sample["path"] for sample in manifest["samples"]}
    assert samples == {"Lightbooth": "Samples~/Lightbooth"}
    assert any(path.suffix == ".cs" for path in (PACKAGE / "Samples~" / "Lightbooth").iterdir())
    assembly = json.loads((PACKAGE / "Runtime" / "VrColourWorkbench.Runtime.asmdef").read_text())
    assert assembly["name"] == "VrColourWorkbench.Runtime" and assembly["autoReferenced"]
    assert "MIT License" in (PACKAGE / "LICENSE.md").read_text()
    assert (PACKAGE / "README.md").is_file()
    project = tomllib.loads((Path(workbench.__file__).parents[1] / "pyproject.toml").read_text())
    assert project["project"]["license"] == "MIT"  # an SPDX expression (PEP 639)


def test_every_bundle_carries_the_whole_package_as_written(simulated_bundle):
    bundle, _ = simulated_bundle
    copied = bundle / "runtime" / "unity"
    files = unity_package_files()
    assert {"package.json", "Runtime/VrColourBundle.cs", "Runtime/Shaders/Level2Relight.hlsl",
            "Runtime/Shaders/VrLevel2Relight.shader"} <= set(files)
    assert sorted(p.relative_to(copied).as_posix() for p in copied.rglob("*") if p.is_file()) \
        == list(files)
    for name in files:
        assert (copied / name).read_bytes() == (PACKAGE / name).read_bytes(), name


def test_an_installed_wheel_would_hold_the_whole_package():
    """pyproject's package-data globs (as setuptools expands them) match every package file."""
    import glob

    root = Path(workbench.__file__).parents[1]
    patterns = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"]["workbench"]
    base = Path(workbench.__file__).parent
    matched = {Path(path).resolve() for pattern in patterns
               for path in glob.glob(str(base / pattern), recursive=True)}
    missing = [name for name in unity_package_files() if (PACKAGE / name).resolve() not in matched]
    assert not missing, missing


def test_every_csharp_file_of_the_package_compiles_against_the_engine_double(engine, tmp_path):
    """Runtime/ as its assembly (VrColourWorkbench.Runtime), Samples~ against it (as Assembly-CSharp)."""
    runtime = sorted((PACKAGE / "Runtime").rglob("*.cs"))
    samples = sorted((PACKAGE / "Samples~").rglob("*.cs"))
    assert len(runtime) >= len(LOADER_SOURCES) and samples
    dll = tmp_path / "VrColourWorkbench.Runtime.dll"
    _mcs("-target:library", f"-r:{engine}", f"-out:{dll}", *runtime)
    _mcs("-target:library", f"-r:{engine}", f"-r:{dll}", f"-out:{tmp_path / 'Samples.dll'}",
         *samples)


# the loader's numbers under mono ---------------------------------------------------------------

def test_every_light_s_rgb8_equals_the_reference_consumer_s(loaded):
    bundle, out, consumer = loaded
    reference = consumer.Bundle(bundle)
    assert list(out["lights"]) == list(BUNDLE_LIGHTS)
    for light_id, light in out["lights"].items():
        rgb8 = reference.light(light_id)
        assert light["rgb8"] == rgb8, light_id
        assert_bits_equal(f32(light["colour"]), np.float32(rgb8 + [255]) / np.float32(255),
                          f"{light_id} Color")


def test_the_light_component_sets_colour_and_intensity_for_each_source(loaded):
    bundle, out, consumer = loaded
    reference = consumer.Bundle(bundle)
    table = {entry["id"]: entry for entry in json.loads((bundle / "lights.json").read_text())["lights"]}
    for unit, runs in out["components"].items():
        for light_id in BUNDLE_LIGHTS:
            run = runs[light_id]
            assert run["rgb8"] == reference.light(light_id), (unit, light_id)
            luminance = np.float32(table[light_id]["XYZ"][1])     # k · Y_white
            intensity = f32(run["intensity"])[0]
            if unit == "EngineUnit":
                assert intensity == 1.0
            else:
                assert intensity == np.float32(np.float32(np.pi) * luminance)
                assert f32(run["ev100"])[0] == pytest.approx(np.log2(luminance / 1.2), rel=1e-6)
        assert runs["events"] == list(BUNDLE_LIGHTS) + [BUNDLE_LIGHTS[0]]
        assert runs["next_after_last"] == BUNDLE_LIGHTS[0] and runs["level1_relit_for"] is None


def test_the_cube_parsed_and_sampled_equals_the_reference_consumer_s(loaded):
    bundle, out, consumer = loaded
    table = consumer.read_cube(bundle / "display_inverse.cube")
    n = table.shape[0]
    cube = out["cube"]
    assert cube["size"] == [n, n, n, n]
    assert_bits_equal(f32(cube["table"]), table, ".cube table")
    assert_bits_equal(f32(cube["texture3d_nodes"]), table, "Texture3D texels (x = r fastest)")
    points = cube_points()
    expected = consumer.trilinear(table, points)
    assert_bits_equal(f32(cube["sample"]), expected, "VrCubeLut.Sample")
    # The Texture3D sampled as a GPU does (texel centres, clamp): at TextureCoordinate(c) =
    # (c·(n−1) + 0.5)/n the GPU's position u·n − 0.5 is c·(n−1) again up to a few float32
    # roundings of a number ≤ n − 1 = 32 (each ≤ 32·2^-24 ≈ 2e-6 of a cell); a node step of the
    # table is ≤ 1, so the value moves by ≤ ~1e-5 — 0.0026 of a DAC count.
    gpu = f32(cube["texture3d_sample"]).reshape(-1, 3)
    assert np.abs(gpu - expected).max() <= 1e-5


def test_the_display_inverse_pre_pass_equals_the_reference_cube_rounded(loaded):
    bundle, out, consumer = loaded
    table = consumer.read_cube(bundle / "display_inverse.cube")
    pixels = authored_pixels()
    dac = consumer.trilinear(table, pixels[:, :3].astype(np.float32) / np.float32(255))
    expected = np.rint(np.clip(dac, 0, 1) * np.float32(255)).astype(np.uint8)
    texels = u8(out["prepass"]["texels"]).reshape(-1, 4)
    np.testing.assert_array_equal(texels[:, :3], expected)
    np.testing.assert_array_equal(texels[:, 3], pixels[:, 3])
    assert out["prepass"]["srgb"] and out["prepass"]["authored_kept"]
    assert not np.array_equal(texels[:, :3], pixels[:, :3])     # the inverse did something


def test_the_display_inverse_tables_are_the_reference_consumer_s(loaded):
    bundle, out, consumer = loaded
    thresholds, cells, correction, domain = consumer.Bundle(bundle).display_inverse()
    inverse = out["inverse"]
    assert inverse["thresholds_size"] == [255, 3] and inverse["cells_size"] == [cells.shape[1], 3]
    assert_bits_equal(f32(inverse["thresholds_texture"]), thresholds, "thresholds texture")
    assert_bits_equal(f32(inverse["thresholds"]), thresholds, "thresholds")
    assert_bits_equal(f32(inverse["cells_texture"]), cells, "cells texture")
    assert_bits_equal(f32(inverse["cells"]), cells, "cells")
    if correction is None:
        assert inverse["correction_size"] == [0] and "correction" not in inverse
    else:
        assert inverse["correction_size"] == [correction.shape[0]]
        assert_bits_equal(f32(inverse["correction_texture"]), correction, "correction Texture3D")
        assert_bits_equal(f32(inverse["correction"]), correction, "correction table")
        assert_bits_equal(f32(inverse["domain"]), domain, "correction domain")


def _reference_after_drive(consumer, bundle, drive, texel_table, unreachable_dac):
    """The reference consumer's level-2 arithmetic from a given float32 drive on (module doc)."""
    thresholds, cells, table, domain = consumer.Bundle(bundle).display_inverse()
    if table is not None:
        low, high = np.float32(domain[0]), np.float32(domain[1])
        drive = consumer.trilinear(table, (drive - low) / (high - low))
    u = np.sqrt(np.clip(drive, np.float32(0.0), np.float32(1.0))).astype(np.float32)
    dac = np.stack([consumer.dac_level(thresholds[c], cells[c], u[:, c]) for c in range(3)], -1)
    return texel_table[np.arange(3), dac].astype(np.uint8), np.any(dac >= unreachable_dac, -1)


def _check_level2(bundle, out, consumer, cube) -> dict:
    """The C# CPU level-2 texels against the reference consumer's; {light: identical share}."""
    reference = consumer.Bundle(bundle)
    level2 = out["level2"]
    shares = {}
    for light_id in BUNDLE_LIGHTS:
        (width, height), planes, matrix, offset, texel_table, unreachable_dac = \
            reference.level2(cube, light_id)
        # the C# planes are rows bottom first (Unity's order); the reference's top first
        flipped = planes.reshape(-1, height, width)[:, ::-1].reshape(planes.shape[0], -1)
        assert_bits_equal(f32(level2["planes"]), flipped, "coefficient channels")
        run = level2[light_id]
        texels = u8(run["texels"]).reshape(height, width, 4)[::-1].reshape(-1, 4)   # top first
        drive = f32(run["drive"]).reshape(height, width, 3)[::-1].reshape(-1, 3)
        # 1. the drive: float32 sums of C products in two orders, within the summation bound
        products = np.abs(planes.T.astype(np.float64)[:, :, None] * matrix.T[None, :, :]).sum(1)
        bound = 2 * planes.shape[0] * EPS32 * (products + np.abs(offset)) + 1e-30
        numpy_drive = planes.astype(np.float32).T @ matrix.T + offset
        assert np.all(np.abs(drive.astype(np.float64) - numpy_drive) <= bound), light_id
        # 2. from its own drive, the C# texel is the reference arithmetic's exactly
        expected, cannot = _reference_after_drive(consumer, bundle, drive, texel_table,
                                                  unreachable_dac)
        np.testing.assert_array_equal(texels[:, :3], expected, err_msg=light_id)
        np.testing.assert_array_equal(texels[:, 3] == 0, cannot, err_msg=light_id)
        assert run["unreachable"] == [int(cannot.sum())]
        # 3. end to end against the reference consumer's own texture: measured
        whole, unreachable = consumer.level2_texture(reference, cube, light_id)
        whole = whole.reshape(-1, 3)
        same = np.all(texels[:, :3] == whole, axis=-1)
        shares[light_id] = float(same.mean())
        assert shares[light_id] >= 0.999, (light_id, shares[light_id])
        assert np.abs(texels[:, :3].astype(int) - whole).max() <= 1, light_id
        # a texel that differs does so because the two drives differ in float32, nowhere else
        assert np.all(np.any(drive[~same] != numpy_drive[~same], axis=-1)), light_id
        assert abs(run["unreachable"][0] - unreachable) <= int((~same).sum())
    print(f"{bundle.name} {cube}: C# CPU level-2 texels identical to the reference consumer's: "
          + ", ".join(f"{k} {100 * v:.3f} %" for k, v in shares.items()))
    return shares


def test_level2_texels_on_the_cpu_path_equal_the_reference_consumer_s(loaded, record_property):
    bundle, out, consumer = loaded
    record_property("identical_level2_texels", _check_level2(bundle, out, consumer, "paint"))


@pytest.mark.slow
def test_the_lightbooth_sample_s_cubes_relight_in_csharp_as_in_the_reference(
        driver, simulated_profile, tmp_path):
    """The ColorChecker board and the Ishihara plate the sample shows, exported and relit in C#."""
    from workbench.export import write_bundle
    from workbench.export.bundle import LIGHTBOOTH_CUBES, lightbooth_cubes

    cubes = lightbooth_cubes()
    assert [name for name, _ in cubes] == list(LIGHTBOOTH_CUBES)
    bundle = tmp_path / "lightbooth"
    write_bundle(simulated_profile, bundle, light_ids=BUNDLE_LIGHTS, cubes=cubes)
    consumer = consumer_module(bundle)
    for cube in LIGHTBOOTH_CUBES:
        result = run_driver(driver, bundle, tmp_path, cube)
        assert result.returncode == 0, result.stderr
        out = json.loads(result.stdout)
        _check_level2(bundle, out, consumer, cube)
        for light_id in BUNDLE_LIGHTS:    # the sample's component path gives the same texels
            assert out["components"]["EngineUnit"][light_id]["albedo"] == \
                out["level2"][light_id]["texels"]


def test_the_level2_component_puts_the_cpu_texels_in_the_material(loaded):
    _, out, _ = loaded
    for unit, runs in out["components"].items():
        for light_id in BUNDLE_LIGHTS:
            run = runs[light_id]
            assert run["relit_for"] == light_id and run["albedo_srgb"]
            assert u8(run["albedo"]).tobytes() == u8(out["level2"][light_id]["texels"]).tobytes()
            assert run["unreachable"] == out["level2"][light_id]["unreachable"]


def test_bind_level2_gives_the_shader_the_bundle_s_numbers(loaded):
    bundle, out, consumer = loaded
    reference = consumer.Bundle(bundle)
    header = json.loads((bundle / "level2" / "paint" / "coefficients.json").read_text())
    layers, height, width = header["layers"], header["height"], header["width"]
    bind = out["bind"]
    assert bind["coefficient_size"] == [width, height, layers]
    raw = np.fromfile(bundle / "level2" / "paint" / "coefficients.bin", dtype="<f2")
    expected_layers = raw.reshape(layers, height, width, 4)[:, ::-1].astype(np.float32)
    assert_bits_equal(f32(bind["coefficient_layers"]), expected_layers, "coefficient layers")
    for light_id in BUNDLE_LIGHTS:
        _, planes, matrix, offset, texel_table, unreachable_dac = reference.level2("paint",
                                                                                   light_id)
        channels = matrix.shape[1]
        padded = np.zeros((3, 4 * 16), np.float32)
        padded[:, :channels] = matrix
        rows = padded.reshape(3, 16, 4).transpose(1, 0, 2)           # [layer][output][i]
        run = bind[light_id]
        assert_bits_equal(f32(run["matrix_rows"]), rows, "_VrMatrixRows")
        assert_bits_equal(f32(run["offset"]), offset, "_VrDriveOffset")
        assert run["layers"][0] == layers
        assert run["layers"][1] == (0 if reference.display_inverse()[2] is None
                                    else reference.display_inverse()[2].shape[0])
        assert_bits_equal(f32(run["unreachable_dac"]), unreachable_dac, "_VrUnreachableDac")
        assert_bits_equal(f32(run["texel_table"]), texel_table, "_VrTexelTable")
        assert run["same_textures"]


def test_components_enabled_before_their_bundle_is_named_log_one_line(loaded):
    _, out, _ = loaded
    assert len(out["log"]) == 3
    assert all(line.startswith("error: Vr") and "bundle.json: missing from the bundle" in line
               for line in out["log"])


def test_a_damaged_bundle_is_one_error_line_and_status_2(driver, simulated_bundle, tmp_path):
    bundle, _ = simulated_bundle
    damaged = tmp_path / "damaged"
    shutil.copytree(bundle, damaged)
    data = (damaged / "level2" / "paint" / "coefficients.bin").read_bytes()
    (damaged / "level2" / "paint" / "coefficients.bin").write_bytes(data[:-8])
    result = run_driver(driver, damaged, tmp_path)
    assert result.returncode == 2, result.stderr
    assert result.stderr.strip().count("\n") == 0
    assert "coefficients.bin" in result.stderr and "truncated" in result.stderr


