"""Who may reach the WebXR server: the token off loopback, loopback Host names, same-origin WebSockets,
one page at a time, TLS with the self-signed certificate."""

from __future__ import annotations

import http.client
import json
import ssl
from pathlib import Path

import pytest

from tests.vr.conftest import PageDriver
from workbench.errors import InputError
from workbench.vr.security import Access, self_signed_certificate
from workbench.vr.server import WebXRServer


def get(port, path, host_header=None, context=None, headers=None):
    connection = (http.client.HTTPSConnection("127.0.0.1", port, timeout=10, context=context) if context
                  else http.client.HTTPConnection("127.0.0.1", port, timeout=10))
    connection.putrequest("GET", path, skip_host=True)
    connection.putheader("Host", host_header or f"127.0.0.1:{port}")
    for name, value in (headers or {}).items():
        connection.putheader(name, value)
    connection.endheaders()
    response = connection.getresponse()
    body = response.read().decode("utf-8", "replace")
    connection.close()
    return response.status, body


def test_off_loopback_every_request_without_the_token_is_refused_with_a_message():
    with WebXRServer(host="0.0.0.0", port=0, tls=False) as server:
        token = server.token
        assert token and len(token) >= 20 and f"/{token}/" in server.url
        for path in ("/", "/static/app.js", "/scene.json", "/ws", "/bundle/lights.json",
                     f"/{token[:-1]}x/", f"/{token}x/static/app.js"):
            status, body = get(server.port, path)
            assert status == 403, path
            assert "403 Forbidden: this server serves only under its token" in body
            assert "open the URL that `python -m workbench vr serve`" in body
        assert get(server.port, f"/{token}/")[0] == 200
        assert get(server.port, f"/{token}/static/app.js")[0] == 200
        assert get(server.port, f"/{token}/scene.json")[0] == 200
        assert get(server.port, f"/{token}", )[0] in (200, 302)


def test_on_loopback_a_foreign_host_name_is_refused():
    with WebXRServer(port=0) as server:
        assert server.token is None
        assert get(server.port, "/")[0] == 200
        assert get(server.port, "/", f"localhost:{server.port}")[0] == 200
        status, body = get(server.port, "/", "attacker.example:80")
        assert status == 403 and "is not this server's loopback address" in body


def test_a_websocket_from_another_origin_is_refused():
    with WebXRServer(port=0) as server:
        headers = {"Connection": "Upgrade", "Upgrade": "websocket", "Sec-WebSocket-Version": "13",
                   "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==", "Origin": "https://attacker.example"}
        status, body = get(server.port, "/ws", headers=headers)
        assert status == 403 and "a WebSocket from the origin 'https://attacker.example'" in body


def test_the_page_reads_only_the_bundle_files_it_needs(vive_bundle):
    with WebXRServer(port=0, bundle=vive_bundle) as server:
        assert get(server.port, "/bundle/lights.json")[0] == 200
        assert get(server.port, "/bundle/level2/lightbooth/coefficients.bin")[0] == 200
        for path in ("/bundle/profile.vrprofile.json", "/bundle/../bundle/lights.json", "/bundle/runtime/README.md",
                     "/bundle/%2e%2e/%2e%2e/etc/passwd"):
            assert get(server.port, path)[0] in (403, 404), path
        scene = json.loads(get(server.port, "/scene.json")[1])
        assert [light["id"] for light in scene["bundle"]["lights"]] == ["cie-d65", "cie-fl11"]


def test_a_second_page_is_told_why_it_is_refused(browser):
    with WebXRServer(port=0) as server:
        first = PageDriver(browser, server.url)
        first.wait("vrWorkbench.state().connected")
        second = PageDriver(browser, server.url)
        second.wait("vrWorkbench.state().refused !== null")
        reason = second.state()["refused"]
        assert reason.startswith(f"busy: this server is showing its page to {server.page.address} (")
        assert "one page at a time; close that page" in reason
        assert second.page.inner_text("#problem") == reason
        assert server.page.serial == 1 and server.page.connected  # the first is not disturbed
        first.close()
        second.close()


def test_a_port_in_use_is_one_clear_message():
    with WebXRServer(port=0) as server:
        with pytest.raises(InputError, match=f"cannot listen on 127.0.0.1:{server.port} .*choose another port"):
            WebXRServer(port=server.port).start()


def test_https_with_the_self_signed_certificate_made_on_first_use(tmp_path):
    with WebXRServer(port=0, tls=True, certificate_folder=tmp_path) as server:
        assert server.url.startswith("https://127.0.0.1:")
        certificate = server.certificate
        context = ssl.create_default_context(cafile=str(certificate.cert_path))
        status, body = get(server.port, "/", context=context, host_header=f"127.0.0.1:{server.port}")
        assert status == 200 and "VR colour workbench" in body
        assert len(certificate.sha256.split(":")) == 32
    again = self_signed_certificate(["127.0.0.1"], tmp_path)
    assert again.sha256 == certificate.sha256  # kept: it covers the name
    other = self_signed_certificate(["192.0.2.7"], tmp_path)
    assert other.sha256 != certificate.sha256 and "192.0.2.7" in other.names


def test_access_rules():
    assert Access.for_host("127.0.0.1", 1).token is None
    assert Access.for_host("::1", 1).token is None
    remote = Access.for_host("0.0.0.0", 5, "abc")
    assert remote.base_path == "/abc/" and remote.path_allowed("/abc/x") and not remote.path_allowed("/abcx")
    local = Access.for_host("127.0.0.1", 5)
    assert local.origin_allowed("http://127.0.0.1:5", "127.0.0.1:5")
    assert not local.origin_allowed("http://127.0.0.1:6", "127.0.0.1:5")
    assert not local.origin_allowed(None, "127.0.0.1:5")
    assert local.host_allowed("[::1]:5") and not local.host_allowed("rebound.example:5")


def test_vr_serve_prints_the_url_and_qr_code_and_stops_on_ctrl_c(tmp_path, vive_bundle):
    import os
    import signal
    import subprocess
    import sys
    import time
    import urllib.request

    from tests.vr.conftest import free_port, wait_listening

    port = free_port()
    root = Path(__file__).resolve().parents[2]
    # Ctrl-C at a terminal: SIGINT at its default action. A test run started as a background job
    # of a non-interactive shell inherits SIGINT ignored, and Python then installs no handler
    process = subprocess.Popen([sys.executable, "-m", "workbench", "vr", "serve", "--port", str(port),
                                "--bundle", str(vive_bundle), "--source", "cie-fl11", "--level", "1"],
                               cwd=root, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "PYTHONIOENCODING": "utf-8"},
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        wait_listening(port)
        scene = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/scene.json", timeout=10).read())
        assert scene["scene"] == {"source": "cie-fl11", "level": 1}
        time.sleep(0.2)
    finally:
        process.send_signal(signal.SIGINT)
        try:
            out, err = process.communicate(timeout=20)
        except subprocess.TimeoutExpired:  # a server that ignored Ctrl-C is not left running
            process.kill()
            process.communicate()
            raise
    assert process.returncode == 0, err
    assert f"Open http://127.0.0.1:{port}/ in the headset's browser (or scan):" in out
    assert "▀" in out or "█" in out  # the QR code
    assert "Lightbooth of" in out and "cie-d65, cie-fl11" in out
