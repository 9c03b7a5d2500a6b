"""APL patches: the optional window and surround fields of the patch protocol, and the headset's limiter."""

import json
import socket

import numpy as np
import pytest

from instruments.headset import (APL_KNEE_LOAD, APL_READ_DELAY_S, APL_TIME_CONSTANT_S, HeadsetError,
                                 SimulatedHeadset, parse_effect, radiance_to_XYZ)
from instruments.patch_display import (PATCH_PROTOCOL, AplPatchesUnsupported, MirroredPatchDisplay,
                                       SimulatedPatchDisplay, TcpPatchDisplay)
from instruments.patch_server import PatchServer


class Recorder:
    """A ``present`` that records what it was asked to show and forwards it to a headset."""

    def __init__(self, headset):
        self.headset = headset
        self.calls = []

    def __call__(self, rgb, **frame):
        self.calls.append((list(rgb), frame))
        self.headset.show(rgb, **frame)


def _Y(headset):
    return radiance_to_XYZ(headset.current_radiance())[1]


@pytest.fixture
def limited():
    return SimulatedHeadset({"apl-dependence": 0.3})


def test_an_apl_patch_reaches_the_headset_through_the_reference_server(limited):
    present = Recorder(limited)
    with PatchServer(present, idle_timeout_s=5.0) as server:
        server.start()
        with TcpPatchDisplay(*server.address, timeout_s=2.0) as display:
            display.show([255, 255, 255], window=0.05, surround=[0, 0, 0])
            small = _Y(limited)
            display.show([255, 255, 255], window=0.5, surround=[128, 128, 128])
            assert limited.shown_window == 0.5 and list(limited.shown_surround) == [128, 128, 128]
            on_grey = _Y(limited)
            display.show([255, 255, 255])
            full = _Y(limited)
    assert present.calls == [([255, 255, 255], {"window": 0.05, "surround": [0, 0, 0]}),
                             ([255, 255, 255], {"window": 0.5, "surround": [128, 128, 128]}),
                             ([255, 255, 255], {})]
    assert small == pytest.approx(100.0, rel=1e-6)  # below the knee: unlimited
    assert full == pytest.approx(70.0, rel=3e-3)     # full-field white loses the magnitude
    assert full < on_grey < small


def test_full_field_patches_go_on_the_wire_exactly_as_before():
    lines = []

    def serve(listener):
        connection, _ = listener.accept()
        with connection, connection.makefile("rwb") as stream:
            for line in stream:
                request = json.loads(line)
                lines.append(request)
                reply = {"ok": True, "id": request["id"]}
                if request["cmd"] == "hello":
                    reply.update(protocol=PATCH_PROTOCOL, display="raw")
                stream.write((json.dumps(reply) + "\n").encode())
                stream.flush()
                if request["cmd"] == "bye":
                    return

    import threading

    with socket.create_server(("127.0.0.1", 0)) as listener:
        thread = threading.Thread(target=serve, args=(listener,), daemon=True)
        thread.start()
        with TcpPatchDisplay(*listener.getsockname()[:2], timeout_s=2.0) as display:
            display.show([1, 2, 3])
            display.show([1, 2, 3], window=1.0, surround=[9, 9, 9])  # a surround behind a full field is invisible
            display.show([4, 5, 6], window=0.25, surround=[7, 8, 9])
        thread.join(2.0)
    shows = [line for line in lines if line["cmd"] == "show"]
    assert shows[0] == {"cmd": "show", "id": 2, "rgb": [1, 2, 3]}
    assert shows[1] == {"cmd": "show", "id": 3, "rgb": [1, 2, 3]}
    assert shows[2] == {"cmd": "show", "id": 4, "rgb": [4, 5, 6], "window": 0.25, "surround": [7, 8, 9]}


def test_an_old_server_refuses_apl_patches_by_name_and_the_client_says_so():
    headset = SimulatedHeadset()
    with PatchServer(lambda rgb: headset.show(rgb), apl_patches=False, idle_timeout_s=5.0) as server:
        server.start()
        with TcpPatchDisplay(*server.address, timeout_s=2.0) as display:
            display.show([10, 20, 30])  # full-field patches still work
            with pytest.raises(AplPatchesUnsupported) as caught:
                display.show([255, 255, 255], window=0.1, surround=[0, 0, 0])
            message = str(caught.value)
            assert "cannot show APL patches" in message and "'window'" in message
            display.show([40, 50, 60])  # the connection stays usable
            assert list(headset.shown) == [40, 50, 60]


def test_the_server_refuses_unknown_and_malformed_fields():
    with PatchServer(lambda rgb, **frame: None, idle_timeout_s=5.0) as server:
        replies = [server.answer(json.dumps(request).encode())[0] for request in (
            {"cmd": "show", "id": 1, "rgb": [1, 2, 3], "blink": True},
            {"cmd": "show", "id": 2, "rgb": [1, 2, 3], "window": 0},
            {"cmd": "show", "id": 3, "rgb": [1, 2, 3], "window": 1.5},
            {"cmd": "show", "id": 4, "rgb": [1, 2, 3], "window": 0.5, "surround": [1, 2]},
            {"cmd": "show", "id": 5, "rgb": [1, 2, 3], "window": 0.5, "surround": [1, 2, 3]},
        )]
    assert [r["ok"] for r in replies] == [False, False, False, False, True]
    assert "unknown field 'blink'" in replies[0]["error"]
    assert "window" in replies[1]["error"] and "window" in replies[2]["error"]


def test_simulated_and_mirrored_displays_pass_the_frame_on(limited):
    plain = SimulatedHeadset()
    MirroredPatchDisplay(SimulatedPatchDisplay(limited), SimulatedPatchDisplay(plain)).show(
        [255, 255, 255], window=0.2, surround=[30, 30, 30])
    assert limited.shown_window == plain.shown_window == 0.2
    assert list(plain.shown_surround) == [30, 30, 30]


def test_a_clean_headset_ignores_the_frame():
    headset = SimulatedHeadset()
    full = radiance_to_XYZ(headset.radiance([255, 255, 255]))
    window = radiance_to_XYZ(headset.radiance([255, 255, 255], window=0.1, surround=[200, 200, 200]))
    assert np.allclose(full, window)


def test_the_limiter_follows_the_load_with_a_knee(limited):
    white = np.array([255.0, 255.0, 255.0])
    assert limited.frame_load(white)[0] == pytest.approx(1.0)
    assert limited.apl_power_shares.sum() == pytest.approx(1.0)
    assert limited.apl_gain(APL_KNEE_LOAD * 0.99) == 1.0
    loads = np.linspace(APL_KNEE_LOAD, 1.0, 20)
    assert np.all(np.diff(limited.apl_gain(loads)) < 0)
    assert limited.apl_gain(1.0) == pytest.approx(0.7)
    # a dark patch on a bright surround is dimmed as much as a white of the same load
    grey_on_white = limited.frame_load([50, 50, 50], window=0.05, surround=[255, 255, 255])[0]
    assert grey_on_white > 0.9


def test_the_limiter_settles_with_its_time_constant():
    clock = [0.0]
    headset = SimulatedHeadset({"apl-dependence": 0.3}, clock=lambda: clock[0])
    headset.show([255, 255, 255], window=0.05)
    clock[0] = 100.0
    headset.show([255, 255, 255])  # full field: the gain falls from 1 to 0.7
    early = _Y(headset)  # read after the instrument's shortest delay
    expected = 70.0 + 30.0 * np.exp(-APL_READ_DELAY_S / APL_TIME_CONSTANT_S)
    assert early == pytest.approx(expected, rel=1e-6)
    clock[0] = 110.0
    assert _Y(headset) == pytest.approx(70.0, rel=1e-6)


def test_the_effect_is_selected_like_the_others():
    assert parse_effect("apl-dependence:0.2") == ("apl-dependence", 0.2)
    assert parse_effect("apl-dependence") == ("apl-dependence", 0.25)
    with pytest.raises(HeadsetError, match="apl-dependence"):
        parse_effect("apl-dependence:1.2")
    with pytest.raises(ValueError, match="window"):
        SimulatedHeadset().radiance([1, 2, 3], window=0.0)
