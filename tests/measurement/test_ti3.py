"""The Argyll .ti3 export: RGB 0-100, XYZ relative to white Y = 100, absolute white in cd/m²."""

import numpy as np
import pytest

from workbench.measurement.ti3 import session_to_ti3_text, write_session_ti3
from workbench.session import Session


def _session():
    return Session(
        kind=["black", "white", "ramp-r", "white"],
        rgb=[[0, 0, 0], [255, 255, 255], [51, 0, 0], [255, 255, 255]],
        XYZ=[[0.1, 0.1, 0.2], [95.0, 100.0, 122.0], [2.0, 1.0, 0.05], [95.2, 101.0, 122.4]],
    )


def _parse(text):
    lines = text.splitlines()
    keywords = dict(line.split(" ", 1) for line in lines if line.startswith(("LUMINANCE", "NORMALIZED", "COLOR_REP")))
    fields = lines[lines.index("BEGIN_DATA_FORMAT") + 1].split()
    start, end = lines.index("BEGIN_DATA"), lines.index("END_DATA")
    rows = np.array([[float(v) for v in line.split()] for line in lines[start + 1:end]])
    n = int(next(line for line in lines if line.startswith("NUMBER_OF_SETS")).split()[1])
    return keywords, fields, rows, n, lines[0]


def test_ti3_values_are_normalised_to_the_white():
    session = _session()
    keywords, fields, rows, n, first = _parse(session_to_ti3_text(session))
    assert first == "CTI3" and n == len(session) == len(rows)
    assert fields == ["SAMPLE_ID", "RGB_R", "RGB_G", "RGB_B", "XYZ_X", "XYZ_Y", "XYZ_Z"]
    white = session.white_XYZ
    assert np.allclose([float(v) for v in keywords["LUMINANCE_XYZ_CDM2"].strip('"').split()], white)
    assert keywords["NORMALIZED_TO_Y_100"] == '"YES"' and keywords["COLOR_REP"] == '"RGB_XYZ"'
    assert np.allclose(rows[:, 1:4], session.rgb / 2.55)
    assert np.allclose(rows[:, 4:], session.XYZ / white[1] * 100, atol=1e-6)
    assert rows[:, 5][session.mask("white")].mean() == pytest.approx(100.0)


def test_write_session_ti3(tmp_path):
    path = write_session_ti3(_session(), tmp_path / "out" / "session.ti3")
    assert path.read_text().startswith("CTI3\n") and not list(path.parent.glob(".*.tmp"))
