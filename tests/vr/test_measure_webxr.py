"""``measure --display webxr:PORT``: a simulated calibration through the page in an emulated headset."""

from __future__ import annotations

import time

import pytest

from tests.vr.conftest import InThread, PageDriver, free_port, wait_listening
from workbench.cli import main
from workbench.measurement.journal import read_journal
from workbench.measurement.runner import JOURNAL_NAME


def measure(*args):
    return ["measure", "--simulate", "--plan", "quick", "--seed", "5", *args]


def run_through_page(browser, port, argv, *, close_after=None, out=None):
    """Run ``main(argv)`` in a thread; open the page, enter VR; optionally close the page once
    ``close_after`` patches are journaled. Returns (exit status, the page driver)."""
    run = InThread(main, argv)
    wait_listening(port)
    page = PageDriver(browser, f"http://127.0.0.1:{port}/")
    page.enter_vr()
    if close_after is not None:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            journal = out / JOURNAL_NAME
            if journal.is_file() and sum(1 for _ in journal.open()) > close_after:
                break
            time.sleep(0.005)
        page.close()
    status = run.result(120)
    return status, page


def test_a_calibration_through_the_page_records_the_same_session_as_the_simulated_display(browser, tmp_path,
                                                                                          capsys):
    assert main(measure("--display", "simulated", "--out", str(tmp_path / "simulated"))) == 0
    port = free_port()
    status, page = run_through_page(browser, port, measure("--display", f"webxr:{port}", "--out",
                                                          str(tmp_path / "webxr")))
    assert status == 0
    captured = capsys.readouterr()
    assert f"webxr: open http://127.0.0.1:{port}/ in the headset's browser and press Enter VR" in captured.err
    assert (tmp_path / "webxr" / "session.csv").read_text() == (tmp_path / "simulated" / "session.csv").read_text()
    webxr = read_journal(tmp_path / "webxr" / JOURNAL_NAME)
    simulated = read_journal(tmp_path / "simulated" / JOURNAL_NAME)
    assert [(r.index, r.rgb, r.XYZ) for r in webxr.records] == [(r.index, r.rgb, r.XYZ) for r in simulated.records]
    assert webxr.header.display.startswith(f"WebXR immersive-vr (emulated quest3), 2 view(s) via webxr:{port}")
    page.wait("vrWorkbench.state().patches === null || !vrWorkbench.state().connected")
    page.close()


def test_a_page_closed_mid_run_stops_it_with_a_message_naming_the_page_and_resume_finishes(browser, tmp_path,
                                                                                           capsys):
    port = free_port()
    out = tmp_path / "session"
    argv = ["measure", "--simulate", "--plan", "paper", "--seed", "7", "--display", f"webxr:{port}",
            "--out", str(out)]
    status, _ = run_through_page(browser, port, argv, close_after=20, out=out)
    assert status == 2
    message = capsys.readouterr().err
    assert "error: the display failed to show" in message
    assert f"the WebXR page at webxr:{port} could not show patch" in message
    assert "the page at 127.0.0.1:" in message and "went away" in message
    assert "run the same command with --resume" in message
    done = len(read_journal(out / JOURNAL_NAME).records)
    assert 20 <= done < 214

    status, page = run_through_page(browser, port, argv + ["--resume"])
    assert status == 0, capsys.readouterr().err
    journal = read_journal(out / JOURNAL_NAME)
    assert not journal.pending_indices() and len(journal.header.plan) == 214
    assert (out / "session.csv").is_file()
    page.close()


def test_webxr_display_addresses():
    from workbench.vr.patch_display import parse_address

    assert parse_address(None) == ("127.0.0.1", 47900)
    assert parse_address("48000") == ("127.0.0.1", 48000)
    assert parse_address("0.0.0.0:48000") == ("0.0.0.0", 48000)
    assert parse_address("[::1]:48000") == ("::1", 48000)
    with pytest.raises(ValueError, match="port 'x'"):
        parse_address("x")
    assert main(["measure", "--simulate", "--display", "webxr:nope", "--out", "x"]) == 2
