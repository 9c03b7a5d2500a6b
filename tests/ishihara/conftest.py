"""Shared, cached fixtures of the Ishihara tests: the plate set and the observers.

The plates are small (the default 192 px; ~270 dots each) and generated once
per session; the simulated headset is calibrated once (through the CS-2000
emulator) by :func:`workbench.ishihara.calibrated_headset`, which caches it.
"""

import pytest

from workbench.ishihara import generate_plate_set, parse_observer


@pytest.fixture(scope="session")
def paper_plates():
    return generate_plate_set()


@pytest.fixture(scope="session")
def observers():
    return {name: parse_observer(name) for name in ("normal", "protan", "deutan")}
