"""Patches in an emulated headset: what the XR framebuffer holds is exactly the DAC, in both eyes.

The page runs in Debian's chromium with IWER's emulated Quest 3 (two views, each
EYE_PX × EYE_PX); with ``?readback=1`` it reads each view back from the XR
framebuffer in the frame that draws a patch and sends, with the
acknowledgement, every distinct colour of each view with its pixel count and
bounding box. The checks below are made here, from those figures.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from instruments.patch_display import PatchDisplayError
from tests.vr.conftest import EYE_PX, InThread
from workbench.vr.patch_display import WebXRPatchDisplay
from workbench.vr.server import WebXRServer

LEVELS = (0, 1, 2, 127, 128, 253, 254, 255)


def channel_patches():
    """0, 1, 2, 127, 128, 253, 254, 255 of each channel alone, and as greys."""
    patches = []
    for level in LEVELS:
        for channel in range(3):
            rgb = [0, 0, 0]
            rgb[channel] = level
            patches.append(rgb)
        patches.append([level] * 3)
    return patches


def random_patches(seed, count=200):
    return np.random.default_rng(seed).integers(0, 256, size=(count, 3)).tolist()


@pytest.fixture(scope="module")
def headset(browser):
    """A server, a page in an emulated immersive session, and the patch display on it."""
    from tests.vr.conftest import PageDriver

    server = WebXRServer(port=0).start()
    page = PageDriver(browser, server.url, readback=True)
    opening = InThread(WebXRPatchDisplay, server, page_timeout_s=60)
    page.enter_vr()
    display = opening.result(60)
    yield display, page
    display.close()
    page.close()
    server.close()


def views(display):
    """``{eye: {rgb tuple: (count, box)}}`` of the last patch, as the page read it back."""
    reply = display.last_reply
    assert reply["ack_frame"] > reply["frame"], "acknowledged in the frame that drew it, not after"
    result = {}
    for view in reply["readback"]:
        assert view["viewport"][2:] == [EYE_PX, EYE_PX]
        result[view["eye"]] = {tuple(c["rgb"]): (c["count"], tuple(c["box"])) for c in view["colours"]}
    assert set(result) == {"left", "right"}
    return result


def assert_full_field(display, rgb, eyes=("left", "right")):
    for eye, colours in views(display).items():
        expected = tuple(rgb) if eye in eyes else (0, 0, 0)
        assert colours == {expected: (EYE_PX * EYE_PX, (0, 0, EYE_PX - 1, EYE_PX - 1))}, (eye, rgb, colours)


def assert_window(display, rgb, window, surround):
    side = EYE_PX * math.sqrt(window)
    for eye, colours in views(display).items():
        if tuple(rgb) == tuple(surround):
            assert colours == {tuple(rgb): (EYE_PX * EYE_PX, (0, 0, EYE_PX - 1, EYE_PX - 1))}
            continue
        assert set(colours) == {tuple(rgb), tuple(surround)}, (eye, rgb, surround, colours)
        count, (x0, y0, x1, y1) = colours[tuple(rgb)]
        width, height = x1 - x0 + 1, y1 - y0 + 1
        assert count == width * height, "the window is not a filled rectangle"
        assert abs(width - side) <= 0.5 and abs(height - side) <= 0.5, (width, height, side)
        assert abs((x0 + x1) / 2 - (EYE_PX - 1) / 2) <= 0.5 and abs((y0 + y1) / 2 - (EYE_PX - 1) / 2) <= 0.5
        assert colours[tuple(surround)][0] == EYE_PX * EYE_PX - count


def test_each_channel_at_the_critical_levels_fills_both_eyes_exactly(headset):
    display, _ = headset
    for rgb in channel_patches():
        display.show(rgb)
        assert_full_field(display, rgb)


def test_two_hundred_random_colours_fill_both_eyes_exactly(headset):
    display, _ = headset
    for rgb in random_patches(17):
        display.show(rgb)
        assert_full_field(display, rgb)


def test_apl_windows_are_centred_on_the_surround_in_both_eyes(headset):
    display, _ = headset
    rng = np.random.default_rng(23)
    patches = channel_patches() + random_patches(29)
    windows = rng.choice([0.01, 0.03, 0.1, 0.2, 0.35, 0.5, 0.75], size=len(patches))
    surrounds = rng.integers(0, 256, size=(len(patches), 3)).tolist()
    surrounds[:8] = [[0, 0, 0]] * 4 + [[128, 128, 128]] * 4
    for rgb, window, surround in zip(patches, windows, surrounds):
        display.show(rgb, window=float(window), surround=surround)
        assert_window(display, rgb, float(window), surround)


@pytest.mark.parametrize("eye", ["left", "right"])
def test_a_patch_for_one_eye_leaves_the_other_black(headset, eye):
    display, _ = headset
    for rgb in channel_patches()[::3] + random_patches(31, 12):
        display.show(rgb, eye=eye)
        assert_full_field(display, rgb, eyes=(eye,))
    display.show([200, 100, 50], window=0.1, surround=[60, 60, 60], eye=eye)
    other = {"left": "right", "right": "left"}[eye]
    seen = views(display)
    assert seen[other] == {(0, 0, 0): (EYE_PX * EYE_PX, (0, 0, EYE_PX - 1, EYE_PX - 1))}
    assert set(seen[eye]) == {(200, 100, 50), (60, 60, 60)}


def test_the_centring_target_is_rings_and_a_cross_on_black(headset):
    display, _ = headset
    display.target()
    for eye, colours in views(display).items():
        assert set(colours) == {(0, 0, 0), (255, 255, 255)}, eye
        white, box = colours[(255, 255, 255)]
        assert box == (0, 0, EYE_PX - 1, EYE_PX - 1)  # the cross reaches the edges
        assert 0.05 < white / EYE_PX ** 2 < 0.3


def test_a_malformed_patch_is_refused_by_the_page_naming_it(headset):
    display, _ = headset
    server = display.server
    reply, _ = server.request({"cmd": "show", "rgb": [1, 2, 300]}, 5, page_serial=display.page.serial)
    assert reply["ok"] is False and "rgb [1,2,300] must be three integers 0..255" in reply["error"]
    reply, _ = server.request({"cmd": "show", "rgb": [1, 2, 3], "gamma": 2}, 5, page_serial=display.page.serial)
    assert reply == {"ok": False, "id": reply["id"],
                     "error": "unknown field 'gamma' in show; this server knows cmd, id, rgb, window, surround, eye"}
    reply, _ = server.request({"cmd": "show", "rgb": [1, 2, 3], "eye": "middle"}, 5, page_serial=display.page.serial)
    assert reply["ok"] is False and "eye" in reply["error"]
    with pytest.raises(ValueError, match="eye 'middle'"):
        display.show([1, 2, 3], eye="middle")
    display.show([5, 6, 7])  # the page goes on showing patches
    assert_full_field(display, [5, 6, 7])


def test_acknowledgement_latency_is_a_frame_or_two(headset):
    display, _ = headset
    display.latencies_s.clear()
    display.page_latencies_ms.clear()
    for level in range(60):
        display.show([level, 255 - level, level])
    latencies = np.array(display.latencies_s) * 1000
    # Chromium headless animates at 60 Hz: the patch is drawn in the next frame and acknowledged
    # in the one after it (one to two frames after the request, and the WebSocket's round trip).
    assert np.median(latencies) < 80, latencies
    assert np.median(display.page_latencies_ms) <= np.median(latencies)
    print(f"request→acknowledgement: median {np.median(latencies):.1f} ms, p95 "
          f"{np.percentile(latencies, 95):.1f} ms (in the page: median {np.median(display.page_latencies_ms):.1f} ms)")


def test_a_page_that_leaves_vr_stops_the_display_with_a_message(browser):
    from tests.vr.conftest import PageDriver

    with WebXRServer(port=0) as server:
        page = PageDriver(browser, server.url)
        opening = InThread(WebXRPatchDisplay, server, page_timeout_s=60)
        page.enter_vr()
        display = opening.result(60)
        display.show([10, 20, 30])
        page.page.evaluate("vrWorkbench.exitVR()")  # as the headset's menu button would
        deadline = time.monotonic() + 10
        while server.page.immersive and time.monotonic() < deadline:
            time.sleep(0.05)
        with pytest.raises(PatchDisplayError, match="left VR"):
            display.show([10, 20, 30])
        display.close()
        page.close()


def test_the_displays_own_eye_goes_with_every_patch_and_the_target(headset):
    display, _ = headset
    display.eye = "right"  # as measure --eye right opens it
    try:
        display.show([90, 180, 45])
        assert_full_field(display, [90, 180, 45], eyes=("right",))
        display.target()
        seen = views(display)
        assert seen["left"] == {(0, 0, 0): (EYE_PX * EYE_PX, (0, 0, EYE_PX - 1, EYE_PX - 1))}
        assert set(seen["right"]) == {(0, 0, 0), (255, 255, 255)}
    finally:
        display.eye = "both"
