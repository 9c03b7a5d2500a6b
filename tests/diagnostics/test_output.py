"""What diagnose says: JSON fields (backwards compatible), terminal and report alike (issue 11, 6 and 8)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from tests.test_diagnostics import REAL, needs_real_data
from workbench.diagnostics import diagnose
from workbench.session import Session, write_session_csv
from workbench.simulated_sessions import simulate_session

FINDING_FIELDS = {"effect", "evidence", "score", "statistic", "standard_error", "z", "p_value",
                  "impact_dE00", "threshold", "in_model"}


@pytest.fixture(scope="module")
def demo_like_csv(tmp_path_factory):
    """The make-demo headset: 10 % channel interaction and a 0.6 % black."""
    session = simulate_session({"channel-interaction": 0.1, "black-offset": 0.006}, seed=1)
    return write_session_csv(session, tmp_path_factory.mktemp("cli") / "session.csv")


def _run(*args):
    return subprocess.run([sys.executable, "-m", "workbench", *args], capture_output=True,
                          text=True, check=True, timeout=300)


def test_json_has_uncertainty_impact_and_noise_and_keeps_the_old_fields(demo_like_csv):
    document = json.loads(_run("diagnose", str(demo_like_csv), "--json").stdout)
    assert {"baseline", "findings", "extended", "gain", "attribution", "fallback"} <= set(document)
    assert {f["effect"] for f in document["findings"]} == {"channel-interaction", "black-offset"}
    for finding in document["findings"]:
        assert FINDING_FIELDS <= set(finding)
        assert finding["z"] > finding["critical_z"] > 2
        assert finding["standard_error"] > 0 and finding["impact_dE00"] >= 0.05
    noise = document["noise"]
    assert noise["source"] == "sweep scatter"
    assert 0.0005 < noise["relative_sd_Y_at_white"] < 0.003  # the emulator's 0.1 % + spectral
    assert "repeatability" in noise["summary"] and "at 1 % of white" in noise["summary"]
    assert document["significance"]["family_alpha"] == 0.05
    assert "unexplained" not in document  # the extension explains this headset


def test_terminal_shows_noise_z_impact_and_what_could_not_be_tested(tmp_path):
    clean = simulate_session(None, seed=5)
    keep = ~clean.mask("black")
    no_black = Session(kind=clean.kind[keep], rgb=clean.rgb[keep], XYZ=clean.XYZ[keep],
                       t_s=clean.t_s[keep], source="no black")
    path = write_session_csv(no_black, tmp_path / "no-black.csv")
    text = _run("diagnose", str(path)).stdout
    assert "noise     repeatability" in text
    assert "untested  black-offset: no black (0, 0, 0) measurement" in text
    assert "tests     a finding needs z above" in text


def test_a_ti3_export_says_drift_is_tested_on_row_order_and_names_no_other_cause(tmp_path):
    from workbench.measurement.ti3 import write_session_ti3

    session = simulate_session({"temporal-drift": 0.05}, seed=1)
    from_csv = diagnose(session)
    path = write_session_ti3(session, tmp_path / "session.ti3")
    text = _run("diagnose", str(path)).stdout
    assert "untested  temporal-drift: tested on row order" in text
    from workbench.session_readers import read_session

    from_ti3 = diagnose(read_session(path))
    assert [f.effect for f in from_ti3.findings] == [f.effect for f in from_csv.findings] == [
        "temporal-drift"]


def test_report_shows_the_same_numbers(tmp_path, demo_like_csv):
    from workbench.diagnostics.report import write_report
    from workbench.session import read_session_csv

    diagnosis = diagnose(read_session_csv(demo_like_csv))
    text = write_report(diagnosis, tmp_path / "r.html").read_text()
    assert "<h2>Noise</h2>" in text and diagnosis.context.noise.describe()[:40] in text
    for finding in diagnosis.findings:
        assert f"z {finding.z:.1f}" in text and f"impact {finding.impact_dE00:.2f}" in text
    assert "<h3>Not tested</h3>" in text


@needs_real_data
def test_an_unexplained_residual_says_how_big_and_what_to_measure():
    from workbench.session_readers import read_session

    diagnosis = diagnose(read_session(
        REAL / "lcd-ti3" / "Apple_MacBookPro13-Late2013_2018-06-03_1459_i1d3_175p.ti3"))
    unexplained = diagnosis.to_json()["unexplained"]
    assert unexplained["effect"] == "unexplained-residual"
    assert unexplained["impact_dE00"] > 0.5
    assert "greys" in unexplained["evidence"] or "mixtures" in unexplained["evidence"]
    assert diagnosis.findings[-1].effect == "unexplained-residual"
    assert np.isclose(unexplained["statistic"], diagnosis.extended_score.mean_dE00)


@pytest.fixture(scope="module")
def knee_csv(tmp_path_factory):
    """A power limit past a knee: channel-interaction is the cause, tone-curve-shape its consequence,
    and the power-limit model is exported."""
    from tests.diagnostics.independent_generator import generate_session

    session = generate_session({"channel-interaction": "knee"}, seed=101, plan="paper").session
    return write_session_csv(session, tmp_path_factory.mktemp("knee") / "knee.csv")


@pytest.fixture(scope="module")
def knee_document(knee_csv):
    return json.loads(_run("diagnose", str(knee_csv), "--json").stdout)


def test_terminal_shows_a_consequence_under_its_cause_and_the_exported_model(knee_csv, knee_document):
    text = _run("diagnose", str(knee_csv)).stdout
    lines = text.splitlines()
    cause = next(i for i, line in enumerate(lines) if line.startswith("finding 1 channel-interaction ("))
    consequence = next(i for i, line in enumerate(lines)
                       if line.startswith("finding 2 tone-curve-shape — consequence of channel-interaction (z "))
    assert cause < consequence
    # the reason is said once, on its own line under the consequence, not again in its evidence
    assert "a consequence of channel-interaction" not in lines[consequence]
    assert lines[consequence + 1].startswith("          ← the bend that channel-interaction's power limit")
    assert text.count("the bend that channel-interaction's power limit puts on the sweeps") == 1
    choice = knee_document["model_choice"]
    assert choice["chosen"] == "power-limit"
    extended = next(i for i, line in enumerate(lines) if line.startswith("extended  "))
    assert lines[extended + 1] == f"model     power-limit exported: {choice['reason']}"
    scores = lines[extended + 2]
    assert scores.startswith("          cross-validated mean ΔE00 on the fit rows: ")
    for name, value in choice["cv_mean_dE00"].items():
        assert f"{name} {value:.3f}" in scores
    assert f"power-limit {choice['cv_mean_dE00']['power-limit']:.3f} (exported)" in scores


def test_report_indents_the_consequence_and_tables_the_model_choice(tmp_path, knee_csv):
    from workbench.diagnostics.report import write_report
    from workbench.session import read_session_csv

    diagnosis = diagnose(read_session_csv(knee_csv))
    assert [f.effect for f in diagnosis.findings] == ["channel-interaction", "tone-curve-shape"]
    text = write_report(diagnosis, tmp_path / "knee.html").read_text()
    findings = text[text.index("<h2>Findings</h2>"):text.index("<h3>Checked")]
    cause = findings.index("<li><b>channel-interaction</b>")
    consequence = findings.index("<li class=consequence><b>tone-curve-shape</b> "
                                 "<span class='tag'>consequence of channel-interaction</span>")
    assert cause < consequence
    assert "li.consequence{margin-left:2em" in text  # indented under its cause
    assert findings.count("the bend that channel-interaction&#x27;s power limit") == 1
    assert "; a consequence of channel-interaction," not in findings
    choice = diagnosis.model_choice.to_json()
    section = text[text.index("<h2>Exported model: power-limit</h2>"):text.index("<h2>Noise</h2>")]
    for name, value in choice["cv_mean_dE00"].items():
        marked = name == "power-limit"
        row = (f"<tr{' class=chosen' if marked else ''}><td>{name}</td>")
        assert row in section and f"<td class=num>{value:.3f}</td>" in section
    assert section.count("✓ exported") == 1
    assert section.index("✓ exported") > section.index("<tr class=chosen><td>power-limit</td>")
