"""The colour-managed lightbooth on the page: level 2 re-authored on the GPU as the reference consumer
computes it, the level-1 light colour as lights.json says, and the source / level switches."""

from __future__ import annotations

import base64
import json
import time
from pathlib import Path

import numpy as np
import pytest

from tests.export.test_conformance import consumer_module
from tests.vr.conftest import InThread, PageDriver
from workbench.vr.scene_cubes import SCENE_CUBE
from workbench.vr.server import WebXRServer


def page_texels(page: PageDriver, light: str) -> np.ndarray:
    answer = page.page.evaluate(f"vrWorkbench.level2Texels({json.dumps(light)})")
    return np.frombuffer(base64.b64decode(answer["rgba"]), np.uint8).reshape(answer["height"], answer["width"], 4)


@pytest.mark.parametrize("bundle_fixture", ["simulated_bundle", "vive_bundle"])
def test_level2_texels_from_the_gpu_equal_the_reference_consumers_for_every_light(browser, request,
                                                                                  bundle_fixture):
    bundle = request.getfixturevalue(bundle_fixture)
    consumer = consumer_module(bundle)
    reader = consumer.Bundle(bundle)
    with WebXRServer(port=0, bundle=bundle) as server:
        page = PageDriver(browser, server.url, emulate=False)
        lights = server.bundle.light_ids()
        assert lights == tuple(reader.manifest["lights"])
        for light in lights:
            texels = page_texels(page, light)
            expected, unreachable = consumer.level2_texture(reader, SCENE_CUBE, light)
            assert texels.shape[:2] == expected.shape[:2]
            different = np.any(texels[..., :3] != expected, axis=-1)
            assert not different.any(), (f"{light}: {different.sum()} of {different.size} texels differ, "
                                         f"largest {np.abs(texels[..., :3].astype(int) - expected).max()}")
            assert int(np.count_nonzero(texels[..., 3] == 0)) == unreachable
        page.close()


def test_the_lamp_shows_the_level1_light_colour_of_lights_json(browser, simulated_bundle):
    table = json.loads((simulated_bundle / "lights.json").read_text())
    with WebXRServer(port=0, bundle=simulated_bundle) as server:
        page = PageDriver(browser, server.url, emulate=False)
        for entry in table["lights"]:
            for level in (1, 2):
                server.set_scene(entry["id"], level)
                page.wait(f"vrWorkbench.state().scene.source === {json.dumps(entry['id'])} && "
                          f"vrWorkbench.state().scene.level === {level}")
                lamp = page.page.evaluate("vrWorkbench.lampPixel()")
                assert lamp["rgb"] == entry["rgb8"], (entry["id"], level, lamp)
        page.close()


def press_trigger_at(page: PageDriver, x: float, y: float, z: float) -> None:
    """Point the emulated right controller along -z from (x, y, z) and press and release its trigger."""
    time.sleep(0.3)  # a few frames after the last release, as a hand would
    page.page.evaluate(f"""(() => {{
        const c = vrWorkbench.emulator.controllers.right;
        c.position.set({x}, {y}, {z}); c.quaternion.set(0, 0, 0, 1);
        c.updateButtonValue('trigger', 1);
        setTimeout(() => c.updateButtonValue('trigger', 0), 100);
    }})()""")


def wait_for_scene(server, expected: dict, timeout_s: float = 10.0) -> dict:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        scene = server.status().scene
        if scene == expected:
            return scene
        time.sleep(0.05)
    raise AssertionError(f"the workbench's scene is {server.status().scene}, not {expected}")


def test_the_source_and_level_switch_in_the_headset_and_from_the_workbench(browser, vive_bundle):
    with WebXRServer(port=0, bundle=vive_bundle) as server:
        changes = []
        server.add_listener(lambda status: changes.append(status.scene))
        page = PageDriver(browser, server.url)
        page.enter_vr()
        assert server.status().scene == {"source": "cie-d65", "level": 2}
        buttons = page.page.evaluate("vrWorkbench.buttons()")  # where the page put them (world, metres)
        x, y, z = buttons["level"]
        press_trigger_at(page, x, y, z + 0.3)
        wait_for_scene(server, {"source": "cie-d65", "level": 1})
        x, y, z = buttons["source"]
        press_trigger_at(page, x, y, z + 0.3)
        wait_for_scene(server, {"source": "cie-fl11", "level": 1})
        press_trigger_at(page, 0.0, 3.0, 0.0)  # pointing at nothing: nothing changes
        time.sleep(0.4)
        assert server.status().scene == {"source": "cie-fl11", "level": 1}
        server.set_scene("cie-d65", 2)  # the Scene page's current source, pushed
        page.wait("vrWorkbench.state().scene.source === 'cie-d65' && vrWorkbench.state().scene.level === 2")
        assert {"source": "cie-fl11", "level": 1} in changes
        page.close()


def test_a_scene_without_the_bundles_light_is_refused(vive_bundle):
    from workbench.errors import InputError

    server = WebXRServer(port=0, bundle=vive_bundle)
    with pytest.raises(InputError, match="source 'cie-a' is not in the bundle"):
        server.set_scene("cie-a")
    with pytest.raises(InputError, match="level 3 must be 1 or 2"):
        server.set_scene(level=3)


def test_the_window_shows_the_scene_without_a_headset(browser, vive_bundle):
    with WebXRServer(port=0, bundle=vive_bundle) as server:
        page = PageDriver(browser, server.url, emulate=False, width=640, height=400)
        page.wait("vrWorkbench.state().connected")
        state = page.state()
        assert not state["immersive"] and not state["problem"]
        assert state["xrNote"].startswith("This browser offers no immersive VR session here")
        shot = page.page.screenshot()
        from io import BytesIO

        from PIL import Image

        pixels = np.asarray(Image.open(BytesIO(shot)).convert("RGB"))
        assert len(np.unique(pixels.reshape(-1, 3), axis=0)) > 50  # a scene, not a cleared window
        assert not page.errors
        page.close()


def test_opening_a_display_on_a_page_that_never_enters_vr_says_what_is_missing(browser):
    from instruments.patch_display import PatchDisplayError
    from workbench.vr.patch_display import WebXRPatchDisplay

    with WebXRServer(port=0) as server:
        page = PageDriver(browser, server.url)
        page.wait("vrWorkbench.state().connected")
        opening = InThread(WebXRPatchDisplay, server, page_timeout_s=1.5)
        with pytest.raises(PatchDisplayError, match="is connected but did not enter VR within 1.5 s"):
            opening.result(30)
        page.close()


def test_a_click_on_the_booths_buttons_in_a_wide_window_switches_source_and_level(browser, vive_bundle):
    """On a window wide enough, the booth is drawn beside the panel (not under it): a click is
    picked in the canvas's own coordinates, so the buttons under the booth still answer."""
    with WebXRServer(port=0, bundle=vive_bundle) as server:
        page = PageDriver(browser, server.url, emulate=False, width=1100, height=620)
        page.wait("vrWorkbench.state().connected && vrWorkbench.state().scene.source !== null")
        box = page.page.evaluate("(() => { const r = document.getElementById('view')"
                                 ".getBoundingClientRect(); return [r.left, r.width]; })()")
        assert box[0] > 300  # beside the panel
        before = page.state()["scene"]
        page.page.mouse.click(615, 484)  # the source button, under the booth's left half
        page.wait(f"vrWorkbench.state().scene.source !== {json.dumps(before['source'])}")
        page.page.mouse.click(884, 484)  # the level button
        page.wait(f"vrWorkbench.state().scene.level !== {before['level']}")
        assert not page.errors
        page.close()
