"""Shared fixtures. Tests run headless; nothing here touches the network."""

from pathlib import Path

import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(20201001)


@pytest.fixture(scope="session")
def playwright_driver():
    """The one Playwright driver of the test process (``tests/vr`` and ``tests/gui`` share it).

    Playwright's sync API runs its asyncio loop in a greenlet of the calling thread, so a
    second driver opened while the first is alive meets a running loop and refuses to start:
    every test that drives chromium takes its browser from this driver.
    """
    sync_api = pytest.importorskip("playwright.sync_api", reason="pip install playwright (the test extra)")
    from tests.vr.conftest import CHROMIUM

    if not Path(CHROMIUM).is_file():
        pytest.skip("Debian's chromium is not installed (apt install chromium)")
    with sync_api.sync_playwright() as driver:
        yield driver


@pytest.fixture(scope="module")
def browser(playwright_driver):
    """One headless chromium (Debian's, software WebGL 2) per test module."""
    from tests.vr.conftest import CHROMIUM, CHROMIUM_ARGS

    chromium = playwright_driver.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)
    yield chromium
    chromium.close()
