"""Measure what identifies it: ``diagnose --follow-up`` proposes, ``measure --add-plan`` measures it
into the same directory, and ``diagnose DIR`` then uses everything.

A paper-plan session of the simulated headset with a hidden channel interaction (what ``make demo``
measures, at time scale 0) cannot identify the interaction's shape; its follow-up of greys and
mixtures can. A clean session gets an empty follow-up; a follow-up killed half-way is finished by
``--resume``; a session with a few windows but too few to test gets the ``apl`` block.
"""

import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from workbench.cli import main
from workbench.diagnostics import diagnose, diagnose_what_it_can
from workbench.diagnostics.extension import interaction_shape
from workbench.diagnostics.follow_up import (
    BUDGET_SHARE,
    DARK_FRACTION,
    GREY_DARK_FRACTION,
    NOTHING_UNIDENTIFIED,
    propose_follow_up,
)
from workbench.errors import InputError, SpectrumFileError
from workbench.measurement.journal import read_journal
from workbench.measurement.plans import GREY_LEVELS, Patch, measurement_plan, read_plan_file
from workbench.measurement.runner import JOURNAL_NAME, MeasurementRun
from workbench.session import Session, read_session_csv
from workbench.session_readers import read_session

from .conftest import RecordingDisplay, ScriptedMeter


def _measure(out, *args):
    return main(["measure", "--simulate", "--time-scale", "0", "--out", str(out), *args])


@pytest.fixture(scope="module")
def interaction_dir(tmp_path_factory):
    """The demo's session without its black: a paper plan hiding a 10 % channel interaction."""
    out = tmp_path_factory.mktemp("interaction") / "session"
    assert _measure(out, "--effect", "channel-interaction:0.1", "--plan", "paper", "--seed", "1") == 0
    return out


@pytest.fixture(scope="module")
def proposed(interaction_dir, tmp_path_factory):
    """``diagnose DIR --follow-up FILE`` on it: (its stdout, the plan file, the diagnosis)."""
    plan = tmp_path_factory.mktemp("plans") / "follow-up.csv"
    assert main(["diagnose", str(interaction_dir), "--follow-up", str(plan)]) == 0
    return plan, diagnose(read_session(interaction_dir))


@pytest.fixture(scope="module")
def followed_dir(interaction_dir, proposed, tmp_path_factory):
    """A copy of the session with its follow-up measured into it: (directory, journal bytes before)."""
    plan, _ = proposed
    out = tmp_path_factory.mktemp("followed") / "session"
    shutil.copytree(interaction_dir, out)
    before = (out / JOURNAL_NAME).read_bytes()
    assert _measure(out, "--add-plan", str(plan)) == 0
    return out, before


def test_a_hidden_interaction_gets_greys_and_mixtures_within_a_quarter_of_the_session(
        interaction_dir, proposed, tmp_path, capsys):
    written, diagnosis = proposed
    assert interaction_shape(diagnosis.context)[1] == "unidentified"
    plan_path = tmp_path / "follow-up.csv"
    capsys.readouterr()
    assert main(["diagnose", str(interaction_dir), "--follow-up", str(plan_path)]) == 0
    out = capsys.readouterr().out
    assert plan_path.read_bytes() == written.read_bytes()
    follow_up = propose_follow_up(diagnosis)
    n = follow_up.patch_count
    assert f"Measure the {n} patches that identify this — about {follow_up.minutes()} min" in out
    assert f"wrote follow-up plan {plan_path} ({n} patches)" in out and "--add-plan" in out

    plan = read_plan_file(plan_path)  # the file reads back as a plan, patch for patch
    assert plan.patches == follow_up.patches
    counts = plan.counts()
    assert set(counts) == {"white", "grey", "mixture"}  # never validation: held-out colours stay unseen
    greys = [p.rgb[0] for p in plan.patches if p.kind == "grey"]
    # the whole ramp, dark greys too: the grey-ramp models take their tone curves from it
    assert all(g in GREY_LEVELS for g in greys) and sum(g / 255 > 0.1 for g in greys) >= 5
    assert min(greys) < 64
    mixtures = [p.rgb for p in plan.patches if p.kind == "mixture"]
    assert len(mixtures) >= 10 and any(min(m) == 0 for m in mixtures) and any(min(m) > 0 for m in mixtures)
    assert plan.patches[0].kind == plan.patches[-1].kind == "white"
    # bright patches only: each mixture at least DARK_FRACTION of white as the model predicts, each
    # grey at least GREY_DARK_FRACTION (the grey ramp must reach into the dark end)
    for kind, floor in (("mixture", DARK_FRACTION), ("grey", GREY_DARK_FRACTION)):
        rgb = np.array([p.rgb for p in plan.patches if p.kind == kind], dtype=float)
        assert np.all(diagnosis.extended.forward(rgb)[:, 1] / diagnosis.white[1] >= floor)
    assert follow_up.serves == ("channel-interaction",)
    assert follow_up.share <= BUDGET_SHARE and follow_up.within_budget
    assert "session's own time per patch" in follow_up.timing  # the session has times
    document = follow_up.to_json()
    assert document["patches"] == n and len(document["plan"]) == n and document["reasons"]


def test_measuring_the_follow_up_appends_it_rewrites_the_session_and_identifies_the_shape(
        interaction_dir, proposed, followed_dir):
    plan_path, before_diagnosis = proposed
    out, before = followed_dir
    plan = read_plan_file(plan_path)
    n, n0 = len(plan), 214
    after = (out / JOURNAL_NAME).read_bytes()
    assert after.startswith(before), "the session's journal lines are unchanged"
    journal = read_journal(out / JOURNAL_NAME)
    assert len(journal.header.plan) == n0 + n and journal.pending_indices() == []
    added = [r for r in journal.records if r.index >= n0]
    assert [r.index for r in added] == list(range(n0, n0 + n)), "exactly the follow-up's patches, once"
    assert [r.patch() for r in added] == list(plan.patches) and all(r.ok for r in added)
    assert len(journal.additions) == 1 and len(journal.additions[0]["add_plan"]["patches"]) == n
    assert after.count(b"\n") == before.count(b"\n") + 1 + n  # one resume record, one line per patch

    session = read_session_csv(out / "session.csv")  # rewritten with every measurement
    assert len(session) == n0 + n and list(session.kind[n0:]) == [p.kind for p in plan.patches]
    assert f"NUMBER_OF_SETS {n0 + n}" in (out / "session.ti3").read_text()

    # the measured instrument time of the follow-up, against the session's own
    session_s = read_journal(interaction_dir / JOURNAL_NAME).session_end_s()
    follow_up_s = journal.session_end_s() - session_s
    estimate = propose_follow_up(before_diagnosis)
    assert follow_up_s / session_s <= BUDGET_SHARE
    assert abs(estimate.instrument_s - follow_up_s) <= 0.25 * follow_up_s  # the estimate holds

    diagnosis = diagnose(read_session(out))  # diagnose DIR now reads the greys too
    assert interaction_shape(diagnosis.context)[1] == "greys"
    assert "channel-interaction" in [f.effect for f in diagnosis.findings]
    assert diagnosis.extended_score.mean_dE00 < before_diagnosis.extended_score.mean_dE00
    assert propose_follow_up(diagnosis).patches == ()


def test_a_clean_session_gets_an_empty_follow_up_a_header_only_file_and_a_message(tmp_path, capsys):
    out = tmp_path / "clean"
    assert _measure(out, "--plan", "quick", "--seed", "3") == 0
    plan_path = tmp_path / "follow-up.csv"
    capsys.readouterr()
    assert main(["diagnose", str(out), "--follow-up", str(plan_path)]) == 0
    said = capsys.readouterr().out
    assert NOTHING_UNIDENTIFIED in said and "the header only, nothing to measure" in said
    assert plan_path.read_text() == "kind,r,g,b\n"
    with pytest.raises(SpectrumFileError, match="nothing to measure"):
        read_plan_file(plan_path)
    assert read_plan_file(plan_path, allow_empty=True).patches == ()

    journal = (out / JOURNAL_NAME).read_bytes()
    assert _measure(out, "--add-plan", str(plan_path)) == 0
    assert "nothing to measure" in capsys.readouterr().out
    assert (out / JOURNAL_NAME).read_bytes() == journal
    assert _measure(tmp_path / "new", "--plan-file", str(plan_path)) == 2  # a new session of nothing
    assert "nothing to measure" in capsys.readouterr().err


def test_a_follow_up_killed_half_way_is_refused_a_second_add_and_finished_by_resume(tmp_path, capsys):
    out = tmp_path / "quick"
    assert _measure(out, "--plan", "quick", "--seed", "4", "--effect", "channel-interaction:0.1") == 0
    plan_path = tmp_path / "follow-up.csv"
    assert main(["diagnose", str(out), "--follow-up", str(plan_path)]) == 0
    said = capsys.readouterr().out
    plan = read_plan_file(plan_path)
    n0, n = 28, len(plan)
    assert n >= 15 and "to keep within 25 % of the session's instrument time" in said  # a short session

    journal_path = out / JOURNAL_NAME
    session_s = read_journal(journal_path).session_end_s()
    lines = journal_path.read_bytes().count(b"\n")
    process = subprocess.Popen([sys.executable, "-m", "workbench", "measure", "--simulate", "--out", str(out),
                                "--add-plan", str(plan_path), "--time-scale", "0.02"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and process.poll() is None:
        if journal_path.read_bytes().count(b"\n") >= lines + 1 + 5:  # the resume record, five patches
            break
        time.sleep(0.002)
    assert process.poll() is None, f"the follow-up ended before the kill: {process.stderr.read().decode()}"
    os.kill(process.pid, signal.SIGKILL)
    process.wait(10)
    killed = read_journal(journal_path)
    assert len(killed.header.plan) == n0 + n and 0 < len(killed.pending_indices()) < n

    assert _measure(out, "--add-plan", str(plan_path)) == 2  # an unfinished session takes no more
    error = capsys.readouterr().err
    assert "not a finished session" in error and "--resume" in error

    assert _measure(out, "--resume") == 0
    assert f"{n0 + n} of {n0 + n} patches measured, 0 failed" in capsys.readouterr().out
    journal = read_journal(journal_path)
    assert sorted(r.index for r in journal.records if r.ok) == list(range(n0 + n))
    assert len(journal.additions) == 1 and len(journal.resumes) == 2
    assert [r.patch() for r in journal.ok_records()[n0:]] == list(plan.patches)
    assert len(read_session_csv(out / "session.csv")) == n0 + n
    assert (journal.session_end_s() - session_s) / session_s <= BUDGET_SHARE  # as measured, not estimated


def test_add_plan_refuses_what_a_resume_refuses_and_says_the_fix(interaction_dir, proposed, tmp_path, capsys):
    plan_path, _ = proposed
    capsys.readouterr()
    cases = [
        (["--simulate", "--out", str(tmp_path / "none"), "--add-plan", str(plan_path)], "holds no journal.jsonl"),
        (["--port", "/dev/null", "--display", "tcp:127.0.0.1:9", "--out", str(interaction_dir),
          "--add-plan", str(plan_path)], "add the plan the same way (--simulate)"),
        (["--simulate", "--effect", "black-offset:0.01", "--out", str(interaction_dir), "--add-plan",
          str(plan_path)], "add it without --effect"),
        (["--simulate", "--resume", "--out", str(interaction_dir), "--add-plan", str(plan_path)],
         "give one of them"),
        (["--simulate", "--seed", "2", "--out", str(interaction_dir), "--add-plan", str(plan_path)],
         "drop --seed"),
    ]
    journal = (interaction_dir / JOURNAL_NAME).read_bytes()
    for args, message in cases:
        assert main(["measure", *args]) == 2, args
        assert message in capsys.readouterr().err
    assert (interaction_dir / JOURNAL_NAME).read_bytes() == journal


def test_the_runner_adds_only_to_a_finished_session_shown_the_same_way(tmp_path):
    from instruments.headset import SimulatedHeadset

    headset = SimulatedHeadset({})
    meter, display = ScriptedMeter(headset), RecordingDisplay(headset)
    quick = measurement_plan("quick", seed=5)
    added = measurement_plan("quick", seed=6)
    run = MeasurementRun.start(tmp_path, quick, display, meter)
    for event in run.events():  # stopped after 3 patches: an unfinished session
        if getattr(event, "done", 0) == 3 and type(event).__name__ == "PatchMeasured":
            run.cancel()
    with pytest.raises(InputError, match="not a finished session"):
        MeasurementRun.resume_session(tmp_path, display, meter, add_plan=added)
    list(MeasurementRun.resume_session(tmp_path, display, meter).events())

    class Elsewhere(RecordingDisplay):
        def describe(self):
            return "another runtime"

    with pytest.raises(InputError, match="shown on 'another runtime'"):
        MeasurementRun.resume_session(tmp_path, Elsewhere(headset), meter, add_plan=added)
    with pytest.raises(InputError, match="holds no patches"):
        MeasurementRun.resume_session(tmp_path, display, meter, add_plan=added.__class__("empty", ()))
    assert len(read_journal(tmp_path / JOURNAL_NAME).resumes) == 1  # nothing written by a refusal
    list(MeasurementRun.resume_session(tmp_path, display, meter, add_plan=added).events())
    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert journal.header.plan.patches == quick.patches + added.patches
    assert journal.header.plan.name == "quick + quick" and journal.pending_indices() == []


def test_a_session_with_too_few_windows_to_test_apl_gets_the_apl_block(interaction_dir, tmp_path):
    base = read_session(interaction_dir)
    grey = base.XYZ[np.all(base.rgb == 255, axis=1)].mean(axis=0) * 0.2
    rows = len(base)
    session = Session(kind=np.r_[base.kind, ["grey"]], rgb=np.vstack([base.rgb, [[128, 128, 128]]]),
                      XYZ=np.vstack([base.XYZ, grey]), t_s=np.r_[base.t_s, base.t_s[-1] + 3],
                      source="with one window", window=np.r_[np.ones(rows), 0.1],
                      surround=np.zeros((rows + 1, 3)))
    diagnosis = diagnose_what_it_can(session)
    apl = next(r for r in diagnosis.results if r.effect == "apl-dependence")
    assert not apl.testable
    follow_up = propose_follow_up(diagnosis)
    block = [p for p in follow_up.patches if p.is_apl or any(p.surround)]
    assert "apl-dependence" in follow_up.serves and len(block) >= 20
    assert Patch("grey", (128, 128, 128), 0.1) not in follow_up.patches  # measured already
    path = follow_up.write(tmp_path / "apl.csv")
    assert path.read_text().splitlines()[0] == "kind,r,g,b,window,sr,sg,sb"
    assert read_plan_file(path).patches == follow_up.patches
    # measured full field only: apl-dependence is not guessed
    assert "apl-dependence" not in propose_follow_up(diagnose(base)).serves


def test_a_session_with_one_white_gets_whites_every_ten_patches_of_its_follow_up(interaction_dir):
    base = read_session(interaction_dir)
    whites = np.flatnonzero(np.all(base.rgb == 255, axis=1))
    diagnosis = diagnose(base.subset(~np.isin(np.arange(len(base)), whites[1:])))
    drift = next(r for r in diagnosis.results if r.effect == "temporal-drift")
    assert not drift.testable
    follow_up = propose_follow_up(diagnosis)
    kinds = [p.kind for p in follow_up.patches]
    assert "temporal-drift" in follow_up.serves and kinds[0] == kinds[-1] == "white"
    gaps = np.diff(np.flatnonzero(np.array(kinds) == "white")) - 1
    assert gaps.max() == 10 and kinds.count("white") >= follow_up.patch_count // 11
