"""Conformance: a runtime following the bundle's files gets the workbench's numbers.

The reference consumer (numpy + json), the GLSL shader executed off-screen,
the HLSL shader compiled to SPIR-V (and executed through spirv-cross), and the
Unity C# loader compiled against a stub of UnityEngine.
"""

import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.export.conftest import BUNDLE_LIGHTS
from tests.export.tools import need_tool
from workbench.colour_management import light_colour
from workbench.export import runtime_display_inverse, runtime_file, runtime_level2_texels
from workbench.export.level2_files import Level2Light
from workbench.hyperspectral import relight_level2_full_band
from workbench.illuminants import get_illuminant

HLSL = "unity/Runtime/Shaders/Level2Relight.hlsl"   # in the Unity package (runtime/unity/)
CONSUMER_IMPORTS = {"argparse", "json", "struct", "sys", "zlib", "pathlib", "numpy"}

# Run the consumer with the workbench (and the profiles package) made unimportable.
_ISOLATED = ("import runpy, sys; sys.modules['workbench'] = None; sys.modules['profiles'] = None; "
             "path = sys.argv[1]; sys.argv = sys.argv[1:]; runpy.run_path(path, run_name='__main__')")


def consumer(bundle: Path, *args: str) -> subprocess.CompletedProcess:
    script = bundle / "runtime" / "reference_consumer.py"
    return subprocess.run([sys.executable, "-I", "-c", _ISOLATED, str(script), str(bundle), *args],
                          capture_output=True, text=True, timeout=120, cwd=bundle)


def consumer_module(bundle: Path):
    import importlib.util

    spec = importlib.util.spec_from_file_location("bundle_reference_consumer",
                                                  bundle / "runtime" / "reference_consumer.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_reference_consumer_imports_only_numpy_and_the_standard_library():
    tree = ast.parse(runtime_file("reference_consumer.py").read_text())
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            imported.add(node.module.split(".")[0])
    assert imported <= CONSUMER_IMPORTS, imported - CONSUMER_IMPORTS


@pytest.mark.parametrize("which", ["simulated_bundle", "vive_bundle"])
def test_level1_light_rgb8_is_the_workbench_s_for_every_light(request, which):
    bundle, _ = request.getfixturevalue(which)
    profile = request.getfixturevalue(which.replace("bundle", "profile"))
    display = profile.display_model()
    for light_id in BUNDLE_LIGHTS:
        result = consumer(bundle, "light", light_id)
        assert result.returncode == 0, result.stderr
        expected = light_colour(get_illuminant(light_id).sd, display, k=profile.k).rgb8
        assert json.loads(result.stdout) == {"rgb8": [int(v) for v in expected]}


@pytest.mark.parametrize("which", ["simulated_bundle", "vive_bundle"])
def test_level2_texture_of_the_consumer_reproduces_relight(request, which, paint_cube, tmp_path):
    bundle, summary = request.getfixturevalue(which)
    profile = request.getfixturevalue(which.replace("bundle", "profile"))
    display = profile.display_model()
    for light_id in BUNDLE_LIGHTS:
        out = tmp_path / f"{light_id}.png"
        result = consumer(bundle, "texture", "paint", "--light", light_id, "--out", str(out))
        assert result.returncode == 0, result.stderr
        texels = np.asarray(Image.open(out).convert("RGB")).astype(int)
        reference = relight_level2_full_band(paint_cube, get_illuminant(light_id), display,
                                             k=profile.k)
        difference = np.abs(texels - reference.texels.astype(int)).max(axis=-1)
        identical = np.mean(difference == 0)
        assert identical >= 0.99, (light_id, identical)
        assert np.mean(difference <= 1) >= 0.995, light_id
        assert json.loads(result.stdout)["unreachable"] == pytest.approx(reference.unreachable,
                                                                         abs=0.01 * texels.size)


def test_consumer_equals_the_workbench_runtime_arithmetic(simulated_bundle, simulated_profile):
    """The files carry exactly what the workbench's in-process runtime emulation used."""
    bundle, _ = simulated_bundle
    module = consumer_module(bundle)
    inverse = runtime_display_inverse(simulated_profile.display_model())
    folder = bundle / "level2" / "paint"
    header = json.loads((folder / "coefficients.json").read_text())
    C, layers, H, W = header["channels"], header["layers"], header["height"], header["width"]
    planes = np.fromfile(folder / "coefficients.bin", dtype="<f2").reshape(layers, H, W, 4)
    planes = planes.transpose(0, 3, 1, 2).reshape(layers * 4, H * W)[:C]
    for record in json.loads((folder / "lights.json").read_text())["lights"]:
        light = Level2Light(record["id"], np.asarray(record["matrix"], np.float32).reshape(3, C).T,
                            np.asarray(record["offset"], np.float32), np.asarray(record["light_rgb8"]),
                            np.asarray(record["texel_table"]).reshape(3, 256),
                            np.asarray(record["unreachable_dac"]))
        expected, unreachable = runtime_level2_texels(planes, light, inverse)
        texels, count = module.level2_texture(module.Bundle(bundle), "paint", record["id"])
        np.testing.assert_array_equal(texels.reshape(-1, 3), expected)
        assert count == unreachable


@pytest.mark.parametrize("which", ["simulated_bundle", "vive_bundle"])
def test_k_is_chosen_for_identical_texels_on_materials_the_basis_never_saw(
        request, which, paint_cube, unseen_cube):
    """The paint cube's basis, applied through the runtime to other materials (CIE TCS, NIST CQS)."""
    from workbench.export import encode_channels, level2_light
    from workbench.hyperspectral import fit_cube_basis

    bundle, summary = request.getfixturevalue(which)
    profile = request.getfixturevalue(which.replace("bundle", "profile"))
    entry = summary.cubes[0]
    display = profile.display_model()
    inverse = runtime_display_inverse(display)
    basis = fit_cube_basis(paint_cube, components=entry["components"], observer=profile.observer,
                           k=profile.k)
    stored = json.loads((bundle / "level2" / "paint" / "basis.json").read_text())
    np.testing.assert_allclose(basis.vectors, stored["vectors"])   # the bundle's basis
    planes = encode_channels(unseen_cube, basis, entry["split"]).reshape(entry["channels"], -1)
    for light_id in BUNDLE_LIGHTS:
        illuminant = get_illuminant(light_id)
        light = level2_light(basis, illuminant, display, inverse, k=profile.k,
                             split=entry["split"])
        runtime, _ = runtime_level2_texels(planes, light, inverse)
        reference = relight_level2_full_band(unseen_cube, illuminant, display,
                                             k=profile.k).texels.reshape(-1, 3)
        identical = np.mean(np.all(runtime == reference, axis=-1))
        assert identical >= 0.99, (light_id, identical)


def run_shader(bundle: Path, mode: str, fragment: Path, tmp_path: Path) -> dict:
    """Execute a relight shader off-screen on the bundle's paint cube under every bundle light,
    in a separate process (glsl_runner.py): {light: (H, W, 4) uint8}. Skips without GL 4.3."""
    out = tmp_path / f"{mode}.npz"
    result = subprocess.run(
        [sys.executable, str(Path(__file__).parent / "glsl_runner.py"), str(bundle), "paint",
         str(out), "--mode", mode, "--fragment", str(fragment),
         "--vertex", str(bundle / "runtime" / "level2_relight.vert"),
         "--lights", ",".join(BUNDLE_LIGHTS)], capture_output=True, text=True, timeout=300)
    if result.returncode == 3:
        pytest.skip(result.stderr.strip())
    assert result.returncode == 0, result.stderr
    with np.load(out) as data:
        return {light: data[light] for light in BUNDLE_LIGHTS}


@pytest.mark.parametrize("which", ["simulated_bundle", "vive_bundle"])
def test_glsl_shader_executed_reproduces_the_numpy_relight(request, which, paint_cube,
                                                           tmp_path):
    bundle, _ = request.getfixturevalue(which)
    profile = request.getfixturevalue(which.replace("bundle", "profile"))
    module = consumer_module(bundle)
    outputs = run_shader(bundle, "glsl", bundle / "runtime" / "level2_relight.frag", tmp_path)
    for light_id in BUNDLE_LIGHTS:
        output = outputs[light_id]
        expected, unreachable = module.level2_texture(module.Bundle(bundle), "paint", light_id)
        assert np.abs(output[..., :3].astype(int) - expected).max() <= 1, light_id
        assert int(np.count_nonzero(output[..., 3] == 0)) == pytest.approx(unreachable, abs=2)
        reference = relight_level2_full_band(paint_cube, get_illuminant(light_id),
                                             profile.display_model(), k=profile.k).texels
        assert np.mean(np.all(output[..., :3] == reference, axis=-1)) >= 0.99, light_id


def _compile_hlsl(source: Path, spirv: Path, entry: str = "main", stage: str = "frag") -> str:
    need_tool("glslangValidator")
    result = subprocess.run(["glslangValidator", "-D", "-V", "-S", stage, "-e", entry,
                             str(source), "-o", str(spirv)], capture_output=True, text=True,
                            timeout=120)
    log = result.stdout + result.stderr
    if result.returncode != 0 or "Entry point not found" in log or "ERROR" in log:
        raise AssertionError(f"HLSL did not compile for entry {entry!r}:\n{log}")
    return log


@pytest.mark.parametrize("entry, stage", [("main", "frag"), ("VrFullScreenTriangle", "vert")])
def test_hlsl_shader_compiles_to_valid_spirv(tmp_path, entry, stage):
    spirv = tmp_path / f"relight-{stage}.spv"
    _compile_hlsl(runtime_file(HLSL), spirv, entry, stage)
    need_tool("spirv-val")
    result = subprocess.run(["spirv-val", str(spirv)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stdout + result.stderr


def test_unity_shader_wraps_the_hlsl_entry_points():
    text = runtime_file("unity/Runtime/Shaders/VrLevel2Relight.shader").read_text()
    hlsl = runtime_file(HLSL).read_text()
    assert '#include "Level2Relight.hlsl"' in text
    for pragma, entry in (("vertex", "VrFullScreenTriangle"), ("fragment", "main")):
        assert f"#pragma {pragma} {entry}" in text
        assert f" {entry}(" in hlsl


def test_a_wrong_entry_point_is_caught_although_the_compiler_exits_0(tmp_path):
    with pytest.raises(AssertionError, match="Entry point not found"):
        _compile_hlsl(runtime_file(HLSL), tmp_path / "x.spv", entry="PSMain")


def test_hlsl_shader_executed_through_spirv_cross(simulated_bundle, tmp_path):
    bundle, _ = simulated_bundle
    spirv = tmp_path / "relight.spv"
    _compile_hlsl(bundle / "runtime" / HLSL, spirv)
    need_tool("spirv-cross")
    glsl = tmp_path / "relight_from_hlsl.frag"
    glsl.write_text(subprocess.run(["spirv-cross", str(spirv), "--version", "430", "--no-es"],
                                   capture_output=True, text=True, check=True, timeout=60).stdout)
    module = consumer_module(bundle)
    outputs = run_shader(bundle, "spirv", glsl, tmp_path)
    for light_id in BUNDLE_LIGHTS:
        output = outputs[light_id]
        expected, _ = module.level2_texture(module.Bundle(bundle), "paint", light_id)
        assert np.abs(output[..., :3].astype(int) - expected).max() <= 1, light_id


def test_unity_loader_compiles_against_a_unityengine_stub(tmp_path):
    mcs = need_tool("mcs")
    stub = Path(__file__).parent / "unity_stub" / "UnityEngine.cs"
    engine = tmp_path / "UnityEngine.dll"
    subprocess.run([mcs, "-langversion:7.2", "-target:library", f"-out:{engine}", str(stub)],
                   check=True, capture_output=True, text=True, timeout=120)
    result = subprocess.run([mcs, "-langversion:7.2", "-target:library", "-warnaserror+",
                             f"-r:{engine}", f"-out:{tmp_path / 'VrColourBundle.dll'}",
                             *(str(runtime_file(f"unity/Runtime/{name}"))   # the loader and its CPU halves
                               for name in ("VrColourBundle.cs", "VrCubeLut.cs", "VrLevel2Cpu.cs"))],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    assert (tmp_path / "VrColourBundle.dll").stat().st_size > 0
