"""The ``ishihara`` command, driven through its own parser (one process, no subprocess)."""

import argparse
import json

import pytest

from workbench.cli import COMMAND_MODULES
from workbench.cli import ishihara as ishihara_cli
from workbench.errors import InputError


def run(argv, capsys):
    parser = argparse.ArgumentParser()
    ishihara_cli.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["ishihara", *argv])
    status = args.handler(args)
    return status, capsys.readouterr().out


def test_command_is_registered():
    assert "workbench.cli.ishihara" in COMMAND_MODULES


def test_generate_then_read(tmp_path, capsys):
    status, out = run(["generate", "--plate", "10", "--out", str(tmp_path), "--size", "128"],
                      capsys)
    assert status == 0 and "classification" in out
    assert {p.name for p in tmp_path.iterdir()} == {"plate_10.npz", "plate_10.png"}
    status, out = run(["read", str(tmp_path / "plate_10.npz"), "--observer", "deutan",
                       "--json"], capsys)
    record = json.loads(out)
    assert record["answer"] == record["reference_answers"]["deutan"] == "2"
    status, out = run(["read", str(tmp_path / "plate_10.npz"), "--observer", "protan:0.3",
                       "--level", "physical"], capsys)
    assert "reads '26'" in out


def test_generate_refuses_a_plate_outside_the_set(tmp_path, capsys):
    with pytest.raises(InputError, match="1 to 10"):
        run(["generate", "--plate", "11", "--out", str(tmp_path)], capsys)


def test_score_json(capsys):
    status, out = run(["score", "--observer", "protan", "--json"], capsys)
    record = json.loads(out)
    assert record["classification"] == "protan"
    assert record["answers"] == ["12", "3", "5", "2", "5", "-", "-", "5", "8", "6"]


def test_score_rejects_an_unknown_level(capsys):
    with pytest.raises(InputError, match="physical"):
        run(["score", "--observer", "normal", "--level", "3"], capsys)


def test_table6_json_layout(capsys):
    status, out = run(["table6", "--json"], capsys)
    record = json.loads(out)
    assert len(record["conditions"]) == 6
    two_peak_level1 = [c for c in record["conditions"]
                       if c["illuminant"] == "d65-two-peak" and c["path"] == "level-1"][0]
    assert two_peak_level1["misleads"] and two_peak_level1["summary"]


def test_table5_text(capsys):
    status, out = run(["table5"], capsys)
    assert "mean ΔE00: ours" in out and "paper 0.96" in out
