"""The journal: header, append + fsync, truncated last line, read back as a session."""

import json

import numpy as np
import pytest

import workbench.measurement.journal as journal_module
from workbench import __version__
from workbench.errors import SpectrumFileError
from workbench.measurement.journal import (
    JOURNAL_FORMAT,
    JournalBusyError,
    JournalHeader,
    JournalRecord,
    JournalWriter,
    journal_to_session,
    read_journal,
)
from workbench.measurement.plans import measurement_plan


def _header():
    return JournalHeader(plan=measurement_plan("quick", seed=4),
                         instrument={"name": "CS-2000", "model": "CS-2000", "serial": "42"},
                         display="simulated", settings={"time_scale": 0})


def _record(index, status="ok", t_s=None):
    patch = _header().plan.patches[index]
    if status != "ok":
        return JournalRecord(index, patch.kind, patch.rgb, "failed", t_s=float(index), duration_s=1.0,
                             reason="CS-2000 ER83: the angle knob is between positions")
    wavelengths = np.arange(380.0, 781.0)
    spectrum = np.full(401, 1e-4 * (index + 1))
    return JournalRecord(index, patch.kind, patch.rgb, "ok", t_s=float(index) if t_s is None else t_s,
                         duration_s=1.0, XYZ=(1.0 + index, 2.0 + index, 3.0), Lv=2.0 + index, xy=(0.3, 0.3),
                         integration_s=0.5, nd_used=False, wavelengths=wavelengths, spectrum=spectrum)


def _write(path, records):
    with JournalWriter.create(path, _header()) as writer:
        for record in records:
            writer.write_record(record)


def test_header_names_plan_instrument_display_version_seed_and_start(tmp_path):
    path = tmp_path / "journal.jsonl"
    _write(path, [])
    header = json.loads(path.read_text().splitlines()[0])
    assert header["record"] == "header" and header["format"] == JOURNAL_FORMAT
    assert header["software"] == f"vr-colour-workbench {__version__}"
    assert header["plan"]["name"] == "quick" and header["plan"]["seed"] == 4
    assert header["plan"]["patches"][0] == ["black", 0, 0, 0]
    assert header["instrument"]["serial"] == "42" and header["display"] == "simulated"
    assert header["started_utc"].endswith("+00:00")


def test_records_round_trip(tmp_path):
    path = tmp_path / "journal.jsonl"
    records = [_record(0), _record(1, "failed"), _record(2)]
    _write(path, records)
    journal = read_journal(path)
    assert journal.header.plan == _header().plan
    assert journal.records == tuple(records)
    assert np.allclose(journal.records[2].spectrum, records[2].spectrum)
    assert np.array_equal(journal.records[2].wavelengths, np.arange(380, 781))
    assert not journal.truncated
    assert [r.index for r in journal.failed_records()] == [1]


def test_every_record_is_fsynced_before_write_record_returns(tmp_path, monkeypatch):
    synced_sizes = []
    real_fsync = journal_module.os.fsync

    def fsync(fd):
        real_fsync(fd)
        synced_sizes.append(journal_module.os.fstat(fd).st_size)

    monkeypatch.setattr(journal_module.os, "fsync", fsync)
    path = tmp_path / "journal.jsonl"
    with JournalWriter.create(path, _header()) as writer:
        for index in range(3):
            writer.write_record(_record(index))
            assert synced_sizes[-1] == path.stat().st_size  # on disk, complete, before the next patch
    assert len([s for s in synced_sizes if s]) >= 4  # header + three records


def test_a_truncated_last_line_is_ignored_and_cut_before_appending(tmp_path):
    path = tmp_path / "journal.jsonl"
    _write(path, [_record(0), _record(1)])
    complete = path.read_bytes()
    line = json.dumps(_record(2).to_json()).encode()
    path.write_bytes(complete + line[: len(line) // 2])  # a crash in the middle of a write
    journal = read_journal(path)
    assert journal.truncated and len(journal.records) == 2 and journal.complete_bytes == len(complete)
    with JournalWriter.append_to(journal) as writer:
        writer.write_record(_record(2))
    data = path.read_bytes()
    assert data.startswith(complete)
    again = read_journal(path)
    assert not again.truncated and [r.index for r in again.records] == [0, 1, 2]
    assert len(again.resumes) == 1 and again.resumes[0]["measured_before"] == 2


def test_a_corrupt_complete_line_is_an_error_naming_the_line(tmp_path):
    path = tmp_path / "journal.jsonl"
    _write(path, [_record(0)])
    path.write_bytes(path.read_bytes() + b"{oops}\n" + json.dumps(_record(1).to_json()).encode() + b"\n")
    with pytest.raises(SpectrumFileError, match="line 3: not a valid journal record") as error:
        read_journal(path)
    assert error.value.fix


def test_a_journal_without_header_or_file_is_an_error(tmp_path):
    with pytest.raises(SpectrumFileError, match="no such journal"):
        read_journal(tmp_path / "journal.jsonl")
    path = tmp_path / "journal.jsonl"
    path.write_text(json.dumps(_record(0).to_json()) + "\n")
    with pytest.raises(SpectrumFileError, match="record before the header"):
        read_journal(path)


def test_create_refuses_to_overwrite_a_journal(tmp_path):
    path = tmp_path / "journal.jsonl"
    _write(path, [_record(0)])
    before = path.read_bytes()
    with pytest.raises(SpectrumFileError, match="already exists.*--resume"):
        JournalWriter.create(path, _header())
    assert path.read_bytes() == before


def test_the_latest_record_of_a_patch_wins_and_pending_skips_measured_ones(tmp_path):
    path = tmp_path / "journal.jsonl"
    _write(path, [_record(0), _record(1, "failed"), _record(2), _record(1, t_s=9.0)])
    journal = read_journal(path)
    assert journal.latest()[1].ok and journal.latest()[1].t_s == 9.0
    assert journal.failed_records() == []
    assert journal.session_end_s() == pytest.approx(10.0)


def test_journal_to_session_keeps_ok_rows_in_plan_order_with_spectra(tmp_path):
    path = tmp_path / "journal.jsonl"
    _write(path, [_record(2), _record(0), _record(1, "failed")])
    session = journal_to_session(read_journal(path))
    assert list(session.kind) == ["black", "ramp-r"]
    assert np.allclose(session.XYZ[:, 0], [1.0, 3.0])
    assert session.spectra.shape == (2, 401) and session.wavelengths[0] == 380
    assert np.allclose(session.t_s, [0.0, 2.0])


def test_a_second_writer_is_refused_while_the_first_is_open(tmp_path):
    path = tmp_path / "journal.jsonl"
    with JournalWriter.create(path, _header()) as first:
        first.write_record(_record(0))
        with pytest.raises(JournalBusyError, match=f"another measure run is writing {path}; wait for it or stop it"):
            JournalWriter.append_to(read_journal(path))
        with pytest.raises(JournalBusyError, match="another measure run is writing"):
            JournalWriter.create(path, _header())  # not "add --resume": that would be refused too
        first.write_record(_record(1))
    assert [r.index for r in read_journal(path).records] == [0, 1]  # the refused writers wrote nothing
    with JournalWriter.append_to(read_journal(path)) as second:  # the lock went with the first writer
        second.write_record(_record(2))
        with pytest.raises(JournalBusyError):
            JournalWriter.append_to(read_journal(path))
    assert [r.index for r in read_journal(path).records] == [0, 1, 2]


def test_a_journal_that_changed_since_it_was_read_is_not_cut(tmp_path):
    path = tmp_path / "journal.jsonl"
    _write(path, [_record(0)])
    stale = read_journal(path)
    with JournalWriter.append_to(read_journal(path)) as other:
        other.write_record(_record(1))
    before = path.read_bytes()
    with pytest.raises(JournalBusyError, match="changed while this run was starting"):
        JournalWriter.append_to(stale)
    assert path.read_bytes() == before


def test_a_record_warning_round_trips_and_the_writer_returns_the_record_as_stored(tmp_path):
    path = tmp_path / "journal.jsonl"
    patch = _header().plan.patches[0]
    record = JournalRecord(0, patch.kind, patch.rgb, "ok", t_s=0.0, duration_s=1.0, XYZ=(0.1, 0.1, 0.1), Lv=0.1,
                           warning="the instrument could not compute the spectral radiance at 1 of 401 wavelengths")
    with JournalWriter.create(path, _header()) as writer:
        stored = writer.write_record(record)
        noisy = _record(1)
        noisy = JournalRecord(**{**noisy.__dict__, "spectrum": noisy.spectrum + 1.234567891e-9})
        stored_noisy = writer.write_record(noisy)
    (read_back, read_noisy) = read_journal(path).records
    assert read_back.warning == record.warning and read_back.spectrum is None
    assert json.loads(path.read_text().splitlines()[1])["warning"] == record.warning
    assert stored == read_back
    assert np.array_equal(stored_noisy.spectrum, read_noisy.spectrum)  # rounded as written
    assert not np.array_equal(noisy.spectrum, read_noisy.spectrum)
