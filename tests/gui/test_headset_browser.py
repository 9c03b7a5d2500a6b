"""The headset's browser (WebXR) in the window: the Calibrate page's patch display "headset browser (WebXR)"
with its URL, QR code and connection state, a calibration through the page in an emulated headset, Cancel
while waiting for it; and the Scene page's "Show in headset browser", sharing the one server.

The page's side is played two ways: by Debian's chromium with the emulated headset (IWER) driven by
Playwright, as ``tests/vr`` does (the calibration; skipped where chromium or Playwright is missing), and by
a WebSocket client speaking ``vr-workbench-webxr/1`` (the connection states and the headset's scene
switches, which need no rendering).
"""

from __future__ import annotations

import asyncio
import json
import socket
import threading
import time

import pytest

from tests.gui import require_window

require_window("pyqtgraph", "aiohttp")

from PySide6.QtCore import Qt  # noqa: E402

from workbench.gui.calibration_setup import open_run  # noqa: E402
from workbench.measurement.journal import read_journal  # noqa: E402
from workbench.measurement.runner import JOURNAL_NAME  # noqa: E402
from workbench.vr.server import PAGE_PROTOCOL, PageState, ServerStatus  # noqa: E402
from workbench.vr.terminal_qr import qr_matrix  # noqa: E402

pytestmark = pytest.mark.gui

RUN_TIMEOUT_MS = 120_000


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _choose_webxr(window, port: int, *, eye: str = "both"):
    """Choose the headset's browser as the patch display, served on 127.0.0.1:``port``."""
    page = window.pages["calibrate"]
    form = page.form
    form.webxr_address.setText(f"127.0.0.1:{port}")
    form.display.setCurrentIndex(form.display.findData("webxr"))
    form.eye.setCurrentIndex(form.eye.findData(eye))
    return page


def _configure_simulated(page, out_dir, *, plan="quick", seed=5, time_scale=0.0):
    form = page.form
    form.instrument.setCurrentIndex(form.instrument.findData("simulated"))
    form.plan.setCurrentIndex(form.plan.findData(plan))
    form.seed.setValue(seed)
    form.time_scale.setValue(time_scale)
    form.out_dir.setText(str(out_dir))


class FakePage:
    """A page of the server played by a WebSocket client (``vr-workbench-webxr/1``) on its own thread."""

    def __init__(self, url: str, *, user_agent: str = "Mozilla/5.0 OculusBrowser/35.1 Chrome/126.0"):
        self.url, self.user_agent = url, user_agent
        self.messages: list = []
        self._loop = asyncio.new_event_loop()
        self._ready = threading.Event()
        self._socket = None
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        assert self._ready.wait(10), "the fake page did not connect"

    def _run(self) -> None:
        asyncio.set_event_loop(self._loop)
        self._loop.run_until_complete(self._main())

    async def _main(self) -> None:
        import aiohttp

        origin = self.url.split("/", 3)
        async with aiohttp.ClientSession() as session:
            async with session.ws_connect(self.url + "ws", headers={"Origin": f"{origin[0]}//{origin[2]}"}) as ws:
                self._socket = ws
                await ws.send_str(json.dumps({"event": "hello", "page": PAGE_PROTOCOL,
                                              "user_agent": self.user_agent, "xr": "webxr"}))
                self._ready.set()
                async for message in ws:
                    if message.type == aiohttp.WSMsgType.TEXT:
                        self.messages.append(json.loads(message.data))

    def send(self, message: dict) -> None:
        async def send():
            await self._socket.send_str(json.dumps(message))
        asyncio.run_coroutine_threadsafe(send(), self._loop).result(5)

    def close(self) -> None:
        if self._socket is not None and not self._socket.closed:
            asyncio.run_coroutine_threadsafe(self._socket.close(), self._loop).result(5)
        self._thread.join(10)


def test_choosing_the_headset_browser_serves_the_page_and_shows_its_url_qr_code_and_state(qtbot, window):
    port = _free_port()
    page = _choose_webxr(window, port, eye="left")
    service = window.headset_browser
    qtbot.waitUntil(lambda: service.running, timeout=10_000)
    server = service.server
    assert (server.host, server.port) == ("127.0.0.1", port) and server.url == f"http://127.0.0.1:{port}/"
    panel = page.headset
    assert panel.isVisible() and panel.url.isVisible() and panel.qr.isVisible()
    assert server.url in panel.url.text()
    assert panel.qr.modules() == qr_matrix(server.url)  # the QR code painted is the URL's, module for module
    assert panel.qr.width() == panel.qr.height() >= 2 * len(qr_matrix(server.url))
    assert panel.state.text() == "waiting for the headset's browser"
    form = page.form
    assert form.webxr_server_button.text() == "Stop server" and not form.webxr_address.isEnabled()
    assert form.eye.isEnabled() and form.eye.isVisibleTo(form)  # a page can show one eye
    setup = form.setup()
    assert (setup.display, setup.webxr_address, setup.eye) == ("webxr", ("127.0.0.1", port), "left")
    assert window.display_label.text() == f"patch display: headset browser at webxr:{port}, left eye"
    # another display hides the panel; the server stays (the Scene page may use it) until stopped
    form.display.setCurrentIndex(form.display.findData("simulated"))
    assert not panel.isVisible() and service.running
    form.display.setCurrentIndex(form.display.findData("webxr"))
    qtbot.mouseClick(form.webxr_server_button, Qt.MouseButton.LeftButton)
    assert not service.running and panel.state.text() == "the page is not served"
    assert form.webxr_server_button.text() == "Start server" and form.webxr_address.isEnabled()


def test_the_state_follows_the_server_from_its_own_thread(qtbot, window):
    """The listener the server calls on its thread reaches the panel through a queued signal."""
    page = _choose_webxr(window, _free_port())
    service = window.headset_browser
    qtbot.waitUntil(lambda: service.running, timeout=10_000)
    server = service.server
    listener = server._listeners[-1]
    connected = ServerStatus(server.url, PageState(serial=1, connected=True, address="192.168.1.20:50000",
                                                   user_agent="Mozilla/5.0 OculusBrowser/35.1 Chrome/126.0"))
    called = threading.Thread(target=listener, args=(connected,))  # as the server's thread calls it
    called.start()
    called.join(5)
    expected = "the page at 192.168.1.20:50000 (OculusBrowser/35.1 Chrome/126.0): connected, not in VR"
    qtbot.waitUntil(lambda: page.headset.state.text().startswith(expected), timeout=5000)
    assert page.headset.state.text() == connected.connection()


def test_the_state_follows_a_page_connecting_entering_vr_and_leaving(qtbot, window):
    page = _choose_webxr(window, _free_port())
    service = window.headset_browser
    qtbot.waitUntil(lambda: service.running, timeout=10_000)
    fake = FakePage(service.server.url)
    try:
        qtbot.waitUntil(lambda: "connected, not in VR (press Enter VR)" in page.headset.state.text(), timeout=5000)
        assert "OculusBrowser/35.1" in page.headset.state.text()
        fake.send({"event": "state", "immersive": True, "views": 2, "eyes": ["left", "right"],
                   "framebuffer": [3680, 1920], "display": "WebXR immersive-vr"})
        qtbot.waitUntil(lambda: page.headset.state.text().endswith(": in VR"), timeout=5000)
    finally:
        fake.close()
    qtbot.waitUntil(lambda: page.headset.state.text() == "waiting for the headset's browser", timeout=5000)


def test_cancel_while_waiting_for_the_headset_stops_the_wait_and_measures_nothing(qtbot, window, tmp_path):
    page = _choose_webxr(window, _free_port())
    _configure_simulated(page, tmp_path / "run")
    qtbot.waitUntil(lambda: window.headset_browser.running, timeout=10_000)
    qtbot.mouseClick(page.start_button, Qt.MouseButton.LeftButton)
    assert page.running and "waiting for the headset's browser to enter VR" in page.patch_label.text()
    qtbot.waitUntil(lambda: window.headset_browser.in_use, timeout=10_000)  # the page is told a run waits
    qtbot.waitUntil(lambda: page.headset.state.text() == "waiting for the headset's browser — a calibration "
                    "is waiting for it", timeout=5000)
    started = time.monotonic()
    qtbot.mouseClick(page.cancel_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not page.running, timeout=10_000)
    assert time.monotonic() - started < 5  # the wait stops, it does not run out its 600 s
    assert page.patch_label.text().startswith("cancelled before the first patch")
    assert "error" not in page.message.text()
    assert not window.headset_browser.in_use and window.headset_browser.running
    assert not (tmp_path / "run" / JOURNAL_NAME).exists()
    assert page.start_button.isEnabled() and page.start_button.text() == "Start"


# -- a calibration through the real page, in chromium with the emulated headset ----------------------------
def test_a_simulated_calibration_through_the_page_in_an_emulated_headset_records_the_simulated_session(
        qtbot, window, tmp_path, browser):
    from tests.vr.conftest import PageDriver

    reference = window.pages["calibrate"].form  # the same session shown on the simulated headset
    page = _choose_webxr(window, _free_port())
    _configure_simulated(page, tmp_path / "webxr")
    qtbot.waitUntil(lambda: window.headset_browser.running, timeout=10_000)
    url = window.headset_browser.server.url
    with open_run(reference.setup(display="simulated", webxr_address=None, out_dir=tmp_path / "simulated")) as run:
        for _ in run.events():
            pass
    qtbot.mouseClick(page.start_button, Qt.MouseButton.LeftButton)
    driver = PageDriver(browser, url)  # the headset's browser opens the URL …
    try:
        qtbot.waitUntil(lambda: "connected, not in VR" in page.headset.state.text(), timeout=20_000)
        driver.enter_vr()  # … and the user presses Enter VR
        with qtbot.waitSignal(page.session_loaded, timeout=RUN_TIMEOUT_MS):
            pass
        assert page.headset.state.text().endswith(": in VR")
        assert not driver.errors, driver.errors
    finally:
        driver.close()
    webxr = read_journal(tmp_path / "webxr" / JOURNAL_NAME)
    simulated = read_journal(tmp_path / "simulated" / JOURNAL_NAME)
    assert [(r.index, r.rgb, r.XYZ) for r in webxr.records] == [(r.index, r.rgb, r.XYZ) for r in simulated.records]
    assert "WebXR immersive-vr (emulated quest3)" in webxr.header.display and " + " in webxr.header.display
    assert page.progress.value() == len(webxr.header.plan) == 28
    assert not window.headset_browser.in_use  # the page is handed back to the scene


# -- the Scene page shares the server --------------------------------------------------------------------
def test_show_in_headset_browser_serves_the_lightbooth_pushes_the_source_and_follows_the_headset(
        qtbot, window):
    calibrate = _choose_webxr(window, _free_port())  # the Calibrate page started the server: no lightbooth
    service = window.headset_browser
    qtbot.waitUntil(lambda: service.running, timeout=10_000)
    port = service.server.port
    scene = window.page("scene")
    assert "served for the calibration, without the lightbooth" in scene.headset.state.text()
    assert not scene.headset_button.isChecked()
    earlier = FakePage(service.server.url)  # a headset has the page open, without a lightbooth
    qtbot.waitUntil(lambda: service.status().page.connected, timeout=5000)
    qtbot.mouseClick(scene.headset_button, Qt.MouseButton.LeftButton)
    assert scene.headset_busy.isVisibleTo(scene) and scene.headset_button.isChecked()
    qtbot.waitUntil(lambda: scene.serving_scene, timeout=RUN_TIMEOUT_MS)
    earlier.close()  # the server restarted with the bundle: that page must be reloaded, and is told so
    server = service.server
    assert server.port == port and server.bundle is not None  # the same address, now with the bundle
    assert set(server.bundle.light_ids()) == set(window.workspace.selected_sources)
    assert server.url in calibrate.headset.url.text()  # one server, one URL, on both pages
    assert server.url in scene.headset.url.text() and scene.headset.qr.modules() == qr_matrix(server.url)
    assert "reload the page in the headset" in scene.headset.state.text()
    # the page's source goes to the headset
    other = next(s for s in server.bundle.light_ids() if s != scene.source_id)
    scene.source_box.setCurrentIndex(scene.source_box.findData(other))
    qtbot.waitUntil(lambda: server.status().scene["source"] == other, timeout=5000)
    # the headset's own switch comes back to the page
    fake = FakePage(server.url)
    try:
        qtbot.waitUntil(lambda: any(m.get("event") == "welcome" for m in fake.messages), timeout=5000)
        assert next(m for m in fake.messages if m.get("event") == "welcome")["scene"]["source"] == other
        back = next(s for s in server.bundle.light_ids() if s != other)
        fake.send({"event": "scene", "source": back, "level": 1})
        qtbot.waitUntil(lambda: scene.source_id == back, timeout=5000)
        assert scene.source_box.currentData() == back
        qtbot.waitUntil(lambda: f"the headset shows {back} at level 1" in scene.headset.state.text(), timeout=5000)
    finally:
        fake.close()
    # again: the server stops, for both pages
    qtbot.mouseClick(scene.headset_button, Qt.MouseButton.LeftButton)
    assert not service.running and not scene.headset_button.isChecked()
    assert calibrate.headset.state.text() == "the page is not served"
