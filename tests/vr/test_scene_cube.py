"""The lightbooth cube (board, plate, wall in one atlas), the bundle check, and the QR code."""

from __future__ import annotations

import numpy as np
import pytest

from workbench.errors import InputError
from workbench.scene.images import scene_content
from workbench.vr.bundle_files import SceneBundle
from workbench.vr.scene_cubes import FRAME_REFLECTANCE, atlas_layout, scene_cube
from workbench.vr.terminal_qr import qr_matrix, qr_text


def test_the_atlas_holds_the_scenes_surfaces_texel_for_texel():
    content = scene_content()
    cube = scene_cube()
    layout = atlas_layout()
    assert [cube.width, cube.height] == layout["size"]
    assert np.array_equal(cube.wavelengths, np.arange(380.0, 781.0, 4.0))
    x, y, w, h = layout["board"]
    labels = content.board_labels
    board = cube.data[y:y + h, x:x + w]
    patch = 13
    inside = labels == patch
    assert np.allclose(board[inside], content.board_reflectances[patch, ::4], atol=1e-6)
    assert np.allclose(board[labels == -1], FRAME_REFLECTANCE)
    x, y, w, h = layout["plate"]
    plate = cube.data[y:y + h, x:x + w]
    for label in (0, 5, int(content.plate_labels.max())):
        assert np.allclose(plate[content.plate_labels == label], content.plate_reflectances[label, ::4], atol=1e-6)
    x, y, w, h = layout["wall"]
    assert np.allclose(cube.data[y:y + h, x:x + w], content.wall_reflectance[0, ::4], atol=1e-6)


def test_a_bundle_without_the_lightbooth_is_refused_naming_the_commands(tmp_path):
    with pytest.raises(InputError, match="no such folder; make one: python -m workbench vr bundle PROFILE"):
        SceneBundle.open(tmp_path / "nothing")
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "bundle.json").write_text(
        '{"format": "vr-colour-workbench-bundle", "format_version": 1, "cubes": [{"name": "paintings"}]}')
    with pytest.raises(InputError, match="has no level-2 'lightbooth' cube \\(it has paintings\\)"):
        SceneBundle.open(tmp_path / "b")
    (tmp_path / "b" / "bundle.json").write_text('{"format": "vr-colour-workbench-bundle", "format_version": 9}')
    with pytest.raises(InputError, match="format_version 9 is not one this page reads"):
        SceneBundle.open(tmp_path / "b")


def test_the_qr_code_encodes_the_url():
    url = "https://192.168.1.20:47900/0123456789abcdefghijkl/"
    rows = qr_matrix(url)
    assert len(rows) == len(rows[0]) and len(rows) >= 25
    text = qr_text(url)
    assert len(text.splitlines()) == (len(rows) + 1) // 2
    plain = qr_text(url, unicode=False)
    assert len(plain.splitlines()) == len(rows) and set(plain) <= {"#", " ", "\n"}
