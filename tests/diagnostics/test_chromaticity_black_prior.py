"""A black read a little off, against a floor estimated low, is no chromaticity shift.

The independent generator's display of seed 30003 has one black row, read (−0.033, 0.001,
0.035) off in XYZ where the session's noise model puts the floor at 0.007: every dark point of
the green sweep moved toward +x alike, and `chromaticity-shift` was named beside a shoulder, a
warm-up, a power limit and a drive crosstalk. A leak toward a fixed chromaticity is still named.
"""

from __future__ import annotations

import pytest

from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics import diagnose


@pytest.mark.parametrize("effects", [{"tone-curve-shape": "shoulder-soft"},
                                     {"temporal-drift": "warm-up"}])
def test_one_black_a_little_off_moves_no_chromaticity(effects):
    diagnosis = diagnose(generate_session(effects, seed=30003, plan="paper+greys").session)
    assert "chromaticity-shift" not in {f.effect for f in diagnosis.findings}, diagnosis.findings


@pytest.mark.parametrize("seed", [30003, 11])
def test_a_leak_is_still_named(seed):
    diagnosis = diagnose(generate_session({"chromaticity-shift": "leak"}, seed=seed,
                                          plan="paper+greys").session)
    assert "chromaticity-shift" in {f.effect for f in diagnosis.findings}
