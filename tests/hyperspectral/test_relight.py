"""Level-2 relighting: the basis kernel against the design's level-2 texel, and its parts."""

from dataclasses import dataclass

import numpy as np
import pytest

from workbench.colour_management import authored_srgb8, level2_texture
from workbench.display import GammaMatrixDisplay, SRGBDisplay, quantize_dac
from workbench.errors import InputError
from workbench.hyperspectral import (
    ACCURACY_SOURCES,
    authored_srgb8_cube,
    channel_inverse_lut,
    encode_cube,
    fit_cube_basis,
    is_channel_separable,
    plan_relight,
    relight_full_band,
    relight_texels,
    write_png_rgb8,
)
from workbench.hyperspectral.png import png_chunks
from workbench.illuminants import get_illuminant
from workbench.profile import paper_vive_profile

DISPLAYS = {"srgb": SRGBDisplay(), "vive": paper_vive_profile().display_model()}


@pytest.fixture(scope="module")
def strict_texture(small_cube):
    # Texel-level agreement is stricter than ΔE: where a light channel is dim (blue under
    # CIE A) level 2 divides by it, and one DAC count becomes several texel counts; a
    # target of 0.05 ΔE00 keeps the DAC flips rare enough.
    basis = fit_cube_basis(small_cube, target_max_dE00=0.05)
    return encode_cube(small_cube, basis)


def _within_one(a, b):
    return np.mean(np.abs(a.astype(int).reshape(-1, 3) - b.astype(int).reshape(-1, 3)).max(-1) <= 1)


@pytest.mark.parametrize("display_id", sorted(DISPLAYS))
@pytest.mark.parametrize("source", ACCURACY_SOURCES)
def test_basis_texels_match_the_level2_reference(small_cube, strict_texture, display_id, source):
    display = DISPLAYS[display_id]
    illuminant = get_illuminant(source)
    texels = relight_texels(strict_texture, plan_relight(strict_texture.basis, illuminant, display))
    assert texels.shape == (small_cube.height, small_cube.width, 3) and texels.dtype == np.uint8
    reference = level2_texture(small_cube.texels(), illuminant.sd, display,
                               wavelengths=small_cube.wavelengths)
    assert _within_one(texels, reference.rgb8) >= 0.99


@pytest.mark.parametrize("source", ["cie-a", "d65-two-peak"])
def test_full_band_path_is_the_level2_reference(small_cube, source):
    illuminant = get_illuminant(source)
    display = DISPLAYS["vive"]
    full = relight_full_band(small_cube, illuminant, display)
    reference = level2_texture(small_cube.texels(), illuminant.sd, display,
                               wavelengths=small_cube.wavelengths)
    assert np.mean(full.reshape(-1, 3) == reference.rgb8) >= 0.999


def test_numba_and_numpy_kernels_agree(strict_texture):
    plan = plan_relight(strict_texture.basis, get_illuminant("cie-fl11"), DISPLAYS["vive"])
    fused = relight_texels(strict_texture, plan, kernel="numba")
    generic = relight_texels(strict_texture, plan, kernel="numpy")
    assert np.mean(fused == generic) >= 0.9999
    out = np.zeros_like(fused)
    assert relight_texels(strict_texture, plan, out=out) is out and np.array_equal(out, fused)
    with pytest.raises(InputError, match="numba"):
        relight_texels(strict_texture, plan, kernel="cuda")


@pytest.mark.parametrize("display_id", sorted(DISPLAYS))
def test_channel_tables_are_the_display_inverse(rng, display_id):
    display = DISPLAYS[display_id]
    lut = channel_inverse_lut(display)
    XYZ = rng.uniform(0, 1, (20000, 3)) * display.white_XYZ
    XYZ[:2000] *= 0.01                                   # plenty of near-black texels
    expected = quantize_dac(display.inverse(XYZ))
    got = lut.dac(XYZ)
    assert np.abs(got - expected).max() <= 1
    assert np.mean(got == expected) >= 0.999


@dataclass(frozen=True, eq=False)
class _CrosstalkDisplay(GammaMatrixDisplay):
    """The paper's model plus a tone curve that leaks red into green: not separable."""

    def dac_from_drive(self, drive):
        drive = np.asarray(drive, dtype=float).copy()
        drive[..., 1] = np.clip(drive[..., 1] + 0.05 * drive[..., 0], 0, 1)
        return super().dac_from_drive(drive)


def test_a_non_separable_display_falls_back_to_its_own_inverse(strict_texture):
    vive = DISPLAYS["vive"]
    display = _CrosstalkDisplay(gamma=vive.gamma, matrix=vive.matrix, white=vive.white)
    assert is_channel_separable(vive) and not is_channel_separable(display)
    plan = plan_relight(strict_texture.basis, get_illuminant("cie-d65"), display)
    assert plan.inverse_lut is None
    with pytest.raises(InputError, match="separable per channel"):
        relight_texels(strict_texture, plan, kernel="numba")
    texels = relight_texels(strict_texture, plan)                   # auto → numpy
    planes = strict_texture.coefficients.reshape(strict_texture.basis.components, -1)
    XYZ = plan.XYZ_offset + planes.T.astype(float) @ plan.XYZ_matrix
    assert np.mean(texels.reshape(-1, 3) == plan.texel_table[np.arange(3),
                                                             quantize_dac(display.inverse(XYZ))]) > 0.999


def test_a_plan_for_another_basis_is_refused(small_cube, strict_texture):
    other = fit_cube_basis(small_cube, components=3)
    with pytest.raises(InputError, match="another basis"):
        relight_texels(strict_texture, plan_relight(other, get_illuminant("cie-a")))


def test_level1_texture_is_the_authored_srgb(small_cube):
    texture = authored_srgb8_cube(small_cube)
    expected = authored_srgb8(small_cube.texels(), wavelengths=small_cube.wavelengths)
    assert np.mean(texture.reshape(-1, 3) == expected) >= 0.999


def test_png_holds_exactly_the_texels(tmp_path, rng):
    import zlib

    rgb = rng.integers(0, 256, (7, 11, 3)).astype(np.uint8)
    path = write_png_rgb8(tmp_path / "t.png", rgb, {"Comment": "test"})
    chunks = dict(png_chunks(path.read_bytes()))
    width, height = np.frombuffer(chunks[b"IHDR"][:8], ">u4")
    assert (height, width) == (7, 11)
    assert chunks[b"tEXt"] == b"Comment\x00test"
    raw = np.frombuffer(zlib.decompress(chunks[b"IDAT"]), np.uint8).reshape(7, 1 + 33)
    assert np.all(raw[:, 0] == 1)                                   # Sub filter
    rows = np.cumsum(raw[:, 1:].reshape(7, 11, 3).astype(np.int64), axis=1) % 256
    np.testing.assert_array_equal(rows, rgb)
    image = pytest.importorskip("PIL.Image")
    np.testing.assert_array_equal(np.asarray(image.open(path).convert("RGB")), rgb)
