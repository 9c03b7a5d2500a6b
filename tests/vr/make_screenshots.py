"""The screenshots of docs/vr/webxr.md, made with the same browser and emulated headset as the tests.

    python -m tests.vr.make_screenshots [docs/screenshots/webxr]

Exports the shipped simulated headset's bundle with the lightbooth cube (into a
temporary folder), serves it, and photographs: the booth in the emulated
headset (both eyes) at level 2 and level 1, an APL patch, the centring target,
one eye's patch, and the page in a desktop window.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from tests.vr.conftest import CHROMIUM, CHROMIUM_ARGS, PROFILES, InThread, PageDriver


def main(out: Path) -> None:
    from playwright.sync_api import sync_playwright

    from workbench.cli import main as workbench
    from workbench.vr.patch_display import WebXRPatchDisplay
    from workbench.vr.server import WebXRServer

    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as work, sync_playwright() as driver:
        bundle = Path(work) / "bundle"
        assert workbench(["vr", "bundle", str(PROFILES / "simulated-headset.vrprofile.json"),
                          "--bundle", str(bundle), "--lights", "cie-d65,cie-a,cie-fl11,d65-two-peak"]) == 0
        browser = driver.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        with WebXRServer(port=0, bundle=bundle) as server:
            window = PageDriver(browser, server.url, emulate=False, width=1100, height=620)
            window.wait("vrWorkbench.state().connected")
            time.sleep(0.5)
            window.page.screenshot(path=str(out / "window-preview.png"))
            window.close()

            page = PageDriver(browser, server.url, width=1200, height=600)
            page.enter_vr()
            server.set_scene("cie-a", 2)
            page.wait("vrWorkbench.state().scene.level === 2 && vrWorkbench.state().scene.source === 'cie-a'")
            time.sleep(0.5)
            page.page.screenshot(path=str(out / "headset-booth-level2-cie-a.png"))
            server.set_scene("cie-a", 1)
            page.wait("vrWorkbench.state().scene.level === 1")
            time.sleep(0.5)
            page.page.screenshot(path=str(out / "headset-booth-level1-cie-a.png"))

            opening = InThread(WebXRPatchDisplay, server, page_timeout_s=30)
            display = opening.result(30)
            display.show([255, 255, 255], window=0.1, surround=[64, 64, 64])
            page.page.screenshot(path=str(out / "headset-apl-patch.png"))
            display.target()
            page.page.screenshot(path=str(out / "headset-target.png"))
            display.show([230, 120, 40], eye="left")
            page.page.screenshot(path=str(out / "headset-left-eye-patch.png"))
            display.close()
            page.close()
        browser.close()
    for path in sorted(out.glob("*.png")):
        print(path)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/screenshots/webxr"))
