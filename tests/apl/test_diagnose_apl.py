"""apl-dependence through ``diagnose``: named with a load term on the independent generator, a held-out
gain at loads the fit did not see, nothing on clean sessions, full-field rows for everything else."""

import numpy as np
import pytest

from tests.apl.generator import generate_paper_apl_session, generate_session, truth_XYZ
from workbench.diagnostics import diagnose, diagnose_what_it_can
from workbench.diagnostics.detectors import family_size
from workbench.diagnostics.load_only import LoadOnlyDiagnosis
from workbench.diagnostics.significance import critical_p, z_of_p

SEEDS = range(3)

# frames none of the sessions measured: windows between the plan's, surrounds between its levels
UNSEEN = [((255, 255, 255), 0.15, (0, 0, 0)), ((255, 255, 255), 0.6, (0, 0, 0)),
          ((200, 200, 200), 0.9, (0, 0, 0)), ((255, 255, 255), 0.05, (96, 96, 96)),
          ((230, 200, 30), 0.25, (0, 0, 0)), ((40, 90, 230), 0.1, (160, 160, 160)),
          ((180, 60, 60), 0.5, (32, 32, 32))]


def _loss(seed):
    return float(np.random.default_rng([20, seed]).uniform(0.1, 0.4))


@pytest.mark.parametrize("seed", SEEDS)
def test_apl_limiting_is_named_with_a_load_term_and_a_held_out_gain(seed):
    loss = _loss(seed)
    diagnosis = diagnose(generate_paper_apl_session(loss, seed))
    (apl,) = [f for f in diagnosis.findings if f.effect == "apl-dependence"]
    assert apl.in_model and apl.impact_dE00 > 0.5 and apl.z > apl.critical_z
    assert "leave one window size out" in apl.cross_validation
    document = diagnosis.to_json()
    assert any(t["effect"] == "apl-dependence" for t in document["extended"]["terms"])
    assert document["apl"]["curve"]["model"] == "soft-power-cap"
    for holdout in diagnosis.apl.holdouts:
        assert holdout.luminance_error_pct < 0.5 * holdout.luminance_error_pct_without, holdout.one_line()
    # patches at loads no row of the session was measured at
    rgb, window, surround = (np.array(v, dtype=float) for v in zip(*UNSEEN))
    truth = truth_XYZ(rgb, window, surround, loss)
    with_term = diagnosis.forward_on_frame(rgb, window, surround)
    without = diagnosis.extended.forward(rgb)  # the full-field prediction: no load term
    error = np.abs(with_term[:, 1] / truth[:, 1] - 1)
    error_without = np.abs(without[:, 1] / truth[:, 1] - 1)
    assert error.mean() < 0.5 * error_without.mean(), (error, error_without)


@pytest.mark.parametrize("seed", SEEDS)
def test_clean_sessions_with_apl_rows_give_no_apl_finding(seed):
    diagnosis = diagnose(generate_paper_apl_session(0.0, seed))
    (apl,) = [r for r in diagnosis.results if r.effect == "apl-dependence"]
    assert apl.testable and not apl.found and not apl.in_model
    assert diagnosis.apl is None and diagnosis.apl_curve is None
    # the other detectors and the model read the full-field rows only, and a testable APL test
    # is one more detector in the family-wise level
    assert np.all(diagnosis.context.fit.window_or_full >= 1)
    assert apl.critical_z == pytest.approx(z_of_p(critical_p(family_size(True))))


def test_sessions_without_windows_keep_their_level_and_say_apl_is_untestable():
    from workbench.simulated_sessions import simulate_session

    diagnosis = diagnose(simulate_session({}, seed=3))
    assert ("apl-dependence" in dict(diagnosis.untested)
            and "'apl'" in dict(diagnosis.untested)["apl-dependence"])
    tested = [r for r in diagnosis.results if r.testable]
    assert tested and all(r.critical_z == pytest.approx(z_of_p(critical_p(5))) for r in tested)


def test_exact_copies_are_not_independent_measurements():
    session = generate_paper_apl_session(0.25, 7)
    doubled = session.subset(np.r_[np.arange(len(session)), np.arange(len(session))])
    z = [next(r.z for r in diagnose(s).results if r.effect == "apl-dependence")
         for s in (session, doubled)]
    assert z[1] == pytest.approx(z[0], rel=1e-6)


@pytest.mark.parametrize("seed", SEEDS)
def test_a_session_with_apl_rows_and_no_ramps_is_diagnosed_for_apl_alone(seed):
    diagnosis = diagnose_what_it_can(generate_session(_loss(seed), seed))
    assert isinstance(diagnosis, LoadOnlyDiagnosis)
    assert [f.effect for f in diagnosis.findings] == ["apl-dependence"]
    assert {e for e, _ in diagnosis.untested} == {"temporal-drift", "black-offset",
                                                  "channel-interaction", "chromaticity-shift",
                                                  "tone-curve-shape"}
    assert all("no display model" in why for _, why in diagnosis.untested)
    document = diagnosis.to_json()
    assert document["baseline"] is None and document["apl"]["holdout"]
    clean = diagnose_what_it_can(generate_session(0.0, seed))
    assert clean.findings == () and clean.apl is None


@pytest.fixture(scope="module")
def apl_profile(tmp_path_factory):
    from workbench.cli.diagnose import export_profile

    diagnosis = diagnose(generate_paper_apl_session(0.3, 1))
    return diagnosis, export_profile(diagnosis, tmp_path_factory.mktemp("apl") / "p.vrprofile.json")


def test_the_profile_records_the_apl_curve_and_predict_applies_it(apl_profile, capsys, monkeypatch):
    import io
    import json

    from workbench.cli import main
    from workbench.profile import load_profile

    diagnosis, path = apl_profile
    profile = load_profile(path)
    block = json.loads(path.read_text())["apl"]
    assert block["reference_load"].startswith("each patch full field")
    assert {h["by"] for h in block["held_out"]} == {"window size", "surround level"}
    assert profile.apl_curve().knee == pytest.approx(diagnosis.apl.curve.knee)
    rows = "r,g,b,window,sr,sg,sb\n255,255,255,1,0,0,0\n255,255,255,0.1,0,0,0\n200,100,50,0.3,64,64,64\n"
    monkeypatch.setattr("sys.stdin", io.StringIO(rows))
    assert main(["predict", str(path)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    XYZ = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    rgb = np.array([[255, 255, 255], [255, 255, 255], [200, 100, 50]], dtype=float)
    expected = diagnosis.forward_on_frame(rgb, np.array([1, 0.1, 0.3]),
                                          np.array([[0, 0, 0], [0, 0, 0], [64, 64, 64]]))
    np.testing.assert_allclose(XYZ, expected, rtol=1e-5)
    assert XYZ[1, 1] > 1.05 * XYZ[0, 1]  # a small white window is brighter than full field


def test_predict_without_an_apl_curve_refuses_windows(capsys, monkeypatch):
    import io
    from pathlib import Path

    from workbench.cli import main

    paper = Path(__file__).resolve().parents[2] / "profiles" / "htc-vive-paper.vrprofile.json"
    monkeypatch.setattr("sys.stdin", io.StringIO("255,255,255,0.1\n"))
    assert main(["predict", str(paper)]) != 0
    assert "no APL curve" in capsys.readouterr().err


def test_a_bad_apl_block_is_refused_by_name(apl_profile):
    import json

    from workbench.profile import ProfileError, parse_profile_text

    _, path = apl_profile
    document = json.loads(path.read_text())
    for change, match in [({"knee": -1.0}, "knee"), ({"power_shares": [0.5, 0.5, 0.5]}, "sum to 1"),
                          ({"transfer": {"method": "linear", "gammas": [1, 1, 1], "peak_cd_m2": 1}},
                           "method")]:
        broken = {**document, "apl": {**document["apl"], **change}}
        with pytest.raises(ProfileError, match=match):
            parse_profile_text(json.dumps(broken), "broken")


def test_the_bundle_carries_the_apl_curve_and_the_light_tables_say_their_load(apl_profile, tmp_path,
                                                                              capsys):
    import json

    from workbench.cli import main
    from workbench.export.bundle import write_bundle
    from workbench.profile import LIGHTS_LOAD, load_profile

    _, path = apl_profile
    write_bundle(load_profile(path), tmp_path / "bundle", lut_size=9)
    manifest = json.loads((tmp_path / "bundle" / "bundle.json").read_text())
    assert manifest["apl"] == json.loads(path.read_text())["apl"]
    assert json.loads((tmp_path / "bundle" / "lights.json").read_text())["load"] == LIGHTS_LOAD
    readme = (tmp_path / "bundle" / "README.md").read_text()
    assert "gain(L_ref)/gain(L)" in readme and "reference load" in readme
    assert main(["illuminants", "show", "cie-d65", "--profile", str(path)]) == 0
    out = capsys.readouterr().out
    assert LIGHTS_LOAD in out and "10 % window" in out


def test_a_found_apl_dependence_is_recorded_beside_its_curve(apl_profile):
    import json

    from workbench.profile import ProfileError, load_profile, parse_profile_text

    _, path = apl_profile
    document = json.loads(path.read_text())
    assert document["apl_test"]["found"] and document["apl_test"]["z"] > document["apl_test"]["critical_z"]
    assert not load_profile(path).apl_tested_absent
    # "not found" beside a curve contradicts itself
    broken = {**document, "apl_test": {**document["apl_test"], "found": False}}
    with pytest.raises(ProfileError, match="apl_test: says apl-dependence was not found"):
        parse_profile_text(json.dumps(broken), "broken")


def _predict(main, path, rows, monkeypatch, capsys):
    import io

    monkeypatch.setattr("sys.stdin", io.StringIO(rows))
    code = main(["predict", str(path)])
    captured = capsys.readouterr()
    XYZ = None if code else np.array([[float(v) for v in line.split(",")]
                                      for line in captured.out.strip().splitlines()[1:]])
    return code, XYZ, captured.err


@pytest.fixture(scope="module")
def clean_apl_profile(tmp_path_factory):
    """A clean simulated headset (no load dependence) measured on ``paper+apl``, diagnosed and exported."""
    from workbench.cli.diagnose import export_profile
    from workbench.simulated_sessions import simulate_session

    diagnosis = diagnose(simulate_session({"black-offset": 0.004}, seed=5, plan="paper+apl"))
    return diagnosis, export_profile(diagnosis, tmp_path_factory.mktemp("clean-apl") / "p.vrprofile.json")


def test_apl_tested_and_absent_is_recorded_and_predict_takes_the_load_columns(clean_apl_profile, capsys,
                                                                               monkeypatch):
    import json

    from workbench.cli import main
    from workbench.profile import load_profile

    diagnosis, path = clean_apl_profile
    assert diagnosis.context.apl_testable and diagnosis.apl is None
    (test,) = [r for r in diagnosis.results if r.effect == "apl-dependence"]
    assert test.testable and not test.found
    document = json.loads(path.read_text())
    assert "apl" not in document
    record = document["apl_test"]
    assert record["found"] is False and record["evidence"] == test.evidence
    assert record["z"] == pytest.approx(test.z) and record["p_value"] == pytest.approx(test.p_value)
    assert record["critical_z"] == pytest.approx(test.critical_z)
    profile = load_profile(path)
    assert profile.apl_tested_absent and profile.apl_curve() is None
    # the same patches full field, as windows on black and on lit surrounds: the same XYZ, no warning
    rgb = ["255,255,255", "255,255,255", "200,100,50", "30,200,90"]
    frames = ["1,0,0,0", "0.1,0,0,0", "0.3,64,64,64", "0.03,255,255,255"]
    code, full, err = _predict(main, path, "r,g,b\n" + "\n".join(rgb) + "\n", monkeypatch, capsys)
    assert code == 0 and err == ""
    code, framed, err = _predict(main, path, "r,g,b,window,sr,sg,sb\n"
                                 + "\n".join(f"{c},{f}" for c, f in zip(rgb, frames)) + "\n",
                                 monkeypatch, capsys)
    assert code == 0 and err == ""
    np.testing.assert_array_equal(framed, full)
    np.testing.assert_allclose(full, profile.display_model().forward(
        np.array([[float(v) for v in c.split(",")] for c in rgb])), rtol=1e-5)


def test_a_profile_never_tested_for_apl_still_refuses_the_load_columns(clean_apl_profile, tmp_path, capsys,
                                                                     monkeypatch):
    import json

    from workbench.cli import main
    from workbench.cli.diagnose import export_profile
    from workbench.profile import load_profile
    from workbench.simulated_sessions import simulate_session

    # a session with every patch full field: nothing tested, nothing recorded
    full_field = export_profile(diagnose(simulate_session({"black-offset": 0.004}, seed=5)),
                                tmp_path / "full-field.vrprofile.json")
    # and the tested profile as an older workbench wrote it (no apl_test record)
    _, path = clean_apl_profile
    document = json.loads(path.read_text())
    del document["apl_test"]
    older = tmp_path / "older.vrprofile.json"
    older.write_text(json.dumps(document))
    for untested in (full_field, older):
        profile = load_profile(untested)
        assert profile.apl_test is None and not profile.apl_tested_absent
        code, _, err = _predict(main, untested, "255,255,255,0.1\n", monkeypatch, capsys)
        assert code != 0 and "the profile has no APL curve, so it predicts full-field patches only" in err
        code, XYZ, _ = _predict(main, untested, "255,255,255\n", monkeypatch, capsys)
        assert code == 0 and XYZ.shape == (1, 3)


def test_the_bundle_and_the_light_tables_say_apl_was_tested_and_absent(clean_apl_profile, tmp_path, capsys):
    import json

    from workbench.cli import main
    from workbench.export.bundle import write_bundle
    from workbench.profile import LIGHTS_LOAD, load_profile

    _, path = clean_apl_profile
    write_bundle(load_profile(path), tmp_path / "bundle", lut_size=9)
    manifest = json.loads((tmp_path / "bundle" / "bundle.json").read_text())
    assert manifest["apl"] is None and manifest["apl_test"] == json.loads(path.read_text())["apl_test"]
    bundled = load_profile(tmp_path / "bundle" / "profile.vrprofile.json")
    assert bundled.apl_tested_absent
    readme = (tmp_path / "bundle" / "README.md").read_text()
    assert "tested `apl-dependence`" in readme and "needs no load compensation" in readme
    assert main(["illuminants", "show", "cie-d65", "--profile", str(path)]) == 0
    out = capsys.readouterr().out
    assert LIGHTS_LOAD in out and "did not find it" in out


def test_the_report_gives_the_apl_curves_held_out_error(apl_profile):
    from workbench.diagnostics.report import render_report

    diagnosis, _ = apl_profile
    page = render_report(diagnosis)
    assert "APL curve (load term)" in page and "leave one window size out" in page


@pytest.mark.parametrize("effects, named", [({"apl-dependence": 0.25}, True), ({}, False)])
def test_the_simulated_headset_measured_on_paper_apl_shows_its_windows(effects, named):
    """simulate_session shows each patch in its window on its surround, as the runner does."""
    from workbench.simulated_sessions import simulate_session

    session = simulate_session(effects, seed=4, plan="paper+apl")
    assert (session.window < 1).any() and (session.surround > 0).any()
    diagnosis = diagnose(session)
    assert ("apl-dependence" in {f.effect for f in diagnosis.findings}) is named
