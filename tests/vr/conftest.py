"""Fixtures of the WebXR tests: Debian's chromium (headless, software WebGL 2) driven by Playwright,
an emulated headset (IWER, vendored), and bundles with the lightbooth cube.

Playwright's own browser download is not used: ``executable_path`` is the system
chromium. A machine without it skips these tests, naming the package.
"""

from __future__ import annotations

import shutil
import socket
import threading
import time
from pathlib import Path

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = ["--enable-unsafe-swiftshader", "--use-angle=swiftshader"]
PROFILES = Path(__file__).resolve().parents[2] / "profiles"
EYE_PX = 160
"""Each eye's viewport in the emulated headset: the page's window is 2 EYE_PX × EYE_PX."""


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def wait_listening(port: int, timeout_s: float = 30.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
            return
        except OSError:
            time.sleep(0.05)
    raise AssertionError(f"nothing listens on 127.0.0.1:{port} after {timeout_s} s")


class PageDriver:
    """A page of the WebXR server in a fresh browser context, with helpers."""

    def __init__(self, browser, url: str, *, emulate=True, readback=False, width=2 * EYE_PX, height=EYE_PX):
        self.context = browser.new_context(viewport={"width": width, "height": height})
        self.page = self.context.new_page()
        self.errors = []
        self.page.on("pageerror", lambda error: self.errors.append(str(error)))
        query = "&".join(part for part in ("emulate=quest3" if emulate else "",
                                           "readback=1" if readback else "") if part)
        self.page.goto(url + (f"?{query}" if query else ""))
        self.page.wait_for_function("window.vrWorkbench && window.vrWorkbench.ready", timeout=30000)

    def state(self) -> dict:
        return self.page.evaluate("vrWorkbench.state()")

    def wait(self, expression: str, timeout_ms: int = 20000) -> None:
        self.page.wait_for_function(expression, timeout=timeout_ms)

    def enter_vr(self) -> None:
        """Press Enter VR (a real click: a user gesture, which requestSession needs) and wait for the session."""
        self.wait("vrWorkbench.state().connected")
        self.page.click("#enter-vr")
        self.wait("vrWorkbench.state().immersive && vrWorkbench.state().eyes.length === 2")

    def close(self) -> None:
        self.context.close()


@pytest.fixture
def open_page(browser):
    pages = []

    def opener(url, **options):
        page = PageDriver(browser, url, **options)
        pages.append(page)
        return page
    yield opener
    for page in pages:
        try:
            page.close()
        except Exception:  # noqa: BLE001 - a test may have closed it already
            pass


@pytest.fixture(scope="session")
def simulated_bundle(tmp_path_factory):
    """The shipped simulated headset's bundle (drive-correction table; its 4 lights) with the lightbooth cube."""
    from workbench.cli import main

    folder = tmp_path_factory.mktemp("bundle") / "simulated"
    assert main(["vr", "bundle", str(PROFILES / "simulated-headset.vrprofile.json"), "--bundle", str(folder)]) == 0
    return folder


@pytest.fixture(scope="session")
def vive_bundle(tmp_path_factory):
    """The paper's HTC Vive (no correction table), two lights, with the lightbooth cube."""
    from workbench.cli import main

    folder = tmp_path_factory.mktemp("bundle") / "vive"
    assert main(["vr", "bundle", str(PROFILES / "htc-vive-paper.vrprofile.json"), "--bundle", str(folder),
                 "--lights", "cie-d65,cie-fl11"]) == 0
    return folder


class InThread:
    """Run ``function`` in a thread; ``result()`` joins it and returns its value or raises its exception."""

    def __init__(self, function, *args, **kwargs):
        self._outcome = {}

        def run():
            try:
                self._outcome["value"] = function(*args, **kwargs)
            except BaseException as error:  # noqa: BLE001 - handed to the test
                self._outcome["error"] = error
        self._thread = threading.Thread(target=run, daemon=True)
        self._thread.start()

    def result(self, timeout_s: float = 120.0):
        self._thread.join(timeout_s)
        assert not self._thread.is_alive(), f"still running after {timeout_s} s"
        if "error" in self._outcome:
            raise self._outcome["error"]
        return self._outcome["value"]
