import json

import numpy as np
import pytest

from profiles import SCHEMA_PATH, example_profile_path
from workbench.profile import ProfileError, load_profile, paper_vive_profile, save_profile


def test_shipped_vive_profile_is_what_the_code_builds():
    shipped = json.loads(example_profile_path("htc-vive-paper").read_text())
    built = paper_vive_profile().to_document()
    assert shipped == json.loads(json.dumps(built))


def test_vive_profile_model_follows_table1():
    model = load_profile(example_profile_path("htc-vive-paper")).display_model()
    xyY = []
    for column in model.matrix.T:
        xyY.append((column[0] / column.sum(), column[1] / column.sum(), column[1]))
    np.testing.assert_allclose(xyY, [(0.667, 0.332, 30.3), (0.217, 0.710, 75.4),
                                     (0.139, 0.051, 7.8)], atol=1e-9)
    np.testing.assert_allclose(model.gamma, [2.43, 2.38, 2.38])
    # the paper's primaries sum to 113.5 % of its white
    assert model.forward([255, 255, 255])[1] / model.white_XYZ[1] == pytest.approx(1.135)


def test_save_load_round_trip(tmp_path):
    path = save_profile(paper_vive_profile(), tmp_path / "p.vrprofile.json")
    again = load_profile(path)
    assert [light["rgb8"] for light in again.lights] == [
        light["rgb8"] for light in paper_vive_profile().lights]


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.pop("display_model"), "'display_model' is a required property"),
    (lambda d: d["engine"].update(k=-1), "engine/k"),
    (lambda d: d["lights"][0].update(rgb8=[300, 0, 0]), "lights/0/rgb8/0"),
    (lambda d: d.update(lut3d={"file": "../../etc/passwd.cube", "size": 17}), "lut3d/file"),
])
def test_invalid_profiles_are_rejected_with_the_place(tmp_path, mutate, message):
    document = paper_vive_profile().to_document()
    mutate(document)
    path = tmp_path / "bad.vrprofile.json"
    path.write_text(json.dumps(document))
    with pytest.raises(ProfileError, match=message):
        load_profile(path)


def test_unreadable_profiles(tmp_path):
    path = tmp_path / "x.vrprofile.json"
    path.write_text("{not json")
    with pytest.raises(ProfileError, match="line 1: not valid JSON"):
        load_profile(path)
    with pytest.raises(ProfileError, match="no such profile"):
        load_profile(tmp_path / "missing.json")


def test_schema_is_valid_json_schema():
    import jsonschema

    jsonschema.Draft202012Validator.check_schema(json.loads(SCHEMA_PATH.read_text()))


def test_an_extended_profile_with_unusable_parameters_is_refused(tmp_path):
    from workbench.cli.diagnose import export_profile
    from workbench.diagnostics import diagnose
    from workbench.simulated_sessions import simulate_session

    path = export_profile(diagnose(simulate_session({"tone-curve-shape": 0.05}, seed=2)),
                          tmp_path / "ok.vrprofile.json")
    document = json.loads(path.read_text())
    assert load_profile(path).display_model().model_id == "extended"
    document["display_model"]["parameters"]["tone"][0] = {"form": "power", "gamma": 0}
    bad = tmp_path / "bad.vrprofile.json"
    bad.write_text(json.dumps(document))
    with pytest.raises(ProfileError, match="tone/0/gamma"):
        load_profile(bad)
