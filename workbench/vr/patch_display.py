"""``--display webxr[:[HOST:]PORT]``: calibration patches in a headset's browser.

:class:`WebXRPatchDisplay` is a patch display (``instruments.patch_display.PatchDisplay``)
that shows each patch on the WebXR page of a :class:`~workbench.vr.server.WebXRServer`:
it waits for a page in an immersive session, sends every patch over the
WebSocket with the fields and rules of ``vr-workbench-patch/1`` (``rgb``; ``window``
and ``surround`` for an APL patch only; ``eye`` only when not both), and returns
once the page says the XR frame showing it has been submitted. As with ``tcp:``:

- the page refusing a patch (``ok: false``) stops the run with a message naming
  the patch and the reason, the journal keeps every measurement, ``--resume`` continues;
- no reply within ``timeout_s`` (10 s) stops the run the same way;
- a page that goes away (tab closed or reloaded, browser asleep, connection lost)
  or leaves VR stops the run with a message naming the page, and ``--resume``
  continues once it is open again (the resumed run serves the page anew and waits for it).

Unlike a TCP patch server it does not reconnect by itself: a new page is a new
browser tab whose XR session the user must start again, so the run stops and says so.
"""

from __future__ import annotations

import sys
import time

from instruments.patch_display import (
    PatchDisplayError,
    is_apl_patch,
    validate_eye,
    validate_patch_rgb,
    validate_patch_window,
)
from workbench.vr.server import DEFAULT_PORT, PageGone, WebXRServer

__all__ = ["WebXRPatchDisplay", "DEFAULT_PAGE_TIMEOUT_S", "SYNTAX", "EXAMPLE", "parse_address", "open_display"]

SYNTAX = "webxr[:[HOST:]PORT]"
"""How ``--display`` spells it."""

EXAMPLE = f"webxr:{DEFAULT_PORT}"

DEFAULT_PAGE_TIMEOUT_S = 600.0
"""How long a measurement waits for the headset's browser to open the page and enter VR."""


def _stderr(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class WebXRPatchDisplay:
    """Shows patches on the WebXR page of ``server`` (module doc).

    Parameters
    ----------
    server : WebXRServer
        A started server.
    timeout_s : float
        Longest wait for each patch's acknowledgement.
    page_timeout_s : float
        Longest wait for a page in an immersive session, on opening.
    client : str
        What the page is told is using it (shown on the page).
    own_server : bool
        Close ``server`` with the display.
    cancel : threading.Event, optional
        Set it to stop waiting for the page (a GUI's Cancel); the display then raises as on a timeout.
    eye : str
        Which eye's panel shows the patches (:data:`~instruments.patch_display.EYES`; the other
        is black); sent with every ``show`` and ``target`` when not ``"both"``.

    Raises
    ------
    PatchDisplayError
        When no page is in VR within ``page_timeout_s``.
    """

    def __init__(self, server: WebXRServer, *, timeout_s: float = 10.0,
                 page_timeout_s: float = DEFAULT_PAGE_TIMEOUT_S, client: str = "vr-workbench",
                 own_server: bool = False, eye: str = "both", cancel=None):
        if not timeout_s > 0 or not page_timeout_s > 0:
            raise ValueError("timeout_s and page_timeout_s must be positive numbers of seconds")
        self.eye = validate_eye(eye)
        self.server = server
        self.timeout_s = float(timeout_s)
        self.own_server = own_server
        self._closed = False
        self.latencies_s: list[float] = []
        self.page_latencies_ms: list[float] = []
        self.last_reply: dict | None = None
        server.attach_patches(client)
        try:
            self.page = server.wait_for_page(page_timeout_s, immersive=True, cancel=cancel)
        except TimeoutError as error:
            self.close()
            raise PatchDisplayError(
                f"{error}: open {server.url} in the headset's browser and press Enter VR (the page says "
                "what it needs), then run the command again") from None

    @classmethod
    def serve(cls, port: int = DEFAULT_PORT, *, host: str = "127.0.0.1", bundle=None, announce=_stderr,
              **options) -> "WebXRPatchDisplay":
        """Start a server on ``host:port``, announce its URL and QR code, and wait for the page.

        ``announce(text)`` receives the lines to show the user (stderr by default).
        """
        from workbench.vr.terminal_qr import qr_text

        server = WebXRServer(host=host, port=port, bundle=bundle).start()
        try:
            if announce is not None:
                encoding = getattr(sys.stderr, "encoding", None) or "ascii"
                unicode = "utf" in encoding.lower()
                announce(f"webxr: open {server.url} in the headset's browser and press Enter VR")
                announce(qr_text(server.url, unicode=unicode))
                if server.certificate is not None:
                    announce(f"webxr: self-signed certificate {server.certificate.cert_path} "
                             f"(SHA-256 {server.certificate.sha256}); trust it once, see docs/vr/webxr.md")
                announce("webxr: waiting for the page to enter VR…")
            return cls(server, own_server=True, **options)
        except BaseException:
            server.close()
            raise

    @property
    def where(self) -> str:
        """``webxr:PORT`` (``webxr:HOST:PORT`` off loopback), as ``--display`` spells it."""
        host = self.server.host
        return f"webxr:{self.server.port}" if host == "127.0.0.1" else f"webxr:{host}:{self.server.port}"

    def _page_problem(self) -> str | None:
        """Why the page cannot show a patch now, or ``None``."""
        now = self.server.page
        if now.serial != self.page.serial or not now.connected:
            return (f"{self.page.describe()} went away (its tab was closed or reloaded, the browser slept, "
                    "or the connection dropped)")
        if not now.immersive:
            return f"{self.page.describe()} left VR (its immersive session ended)"
        return None

    def _fail(self, what: str, reason: str) -> PatchDisplayError:
        return PatchDisplayError(
            f"the WebXR page at {self.where} could not show {what}: {reason}; open {self.server.url} in the "
            "headset's browser again and press Enter VR before resuming")

    def _request(self, message: dict, what: str) -> dict:
        if self._closed:
            raise PatchDisplayError(f"the patch display {self.where} has been closed")
        problem = self._page_problem()
        if problem:
            raise self._fail(what, problem)
        started = time.perf_counter()
        try:
            reply, _ = self.server.request(message, self.timeout_s, page_serial=self.page.serial)
        except PageGone:
            raise self._fail(what, self._page_problem() or f"{self.page.describe()} went away") from None
        except TimeoutError:
            raise PatchDisplayError(
                f"the WebXR page at {self.where} did not acknowledge {what} within {self.timeout_s:g} s "
                f"({self.page.describe()}); check that the headset is on and the page in VR, then resume"
            ) from None
        if reply.get("ok") is not True:
            reason = str(reply.get("error", "no reason given"))
            problem = self._page_problem()
            raise self._fail(what, problem or f"the page refused it: {reason}")
        self.latencies_s.append(time.perf_counter() - started)
        if isinstance(reply.get("page_ms"), (int, float)):
            self.page_latencies_ms.append(float(reply["page_ms"]))
        self.last_reply = reply
        return reply

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0), eye: str | None = None) -> None:
        """Show ``rgb_dac`` (as ``window`` on ``surround``, to :attr:`eye` or ``eye``); return once the
        page has submitted the XR frame that shows it."""
        request = {"cmd": "show", "rgb": validate_patch_rgb(rgb_dac)}
        if is_apl_patch(window, surround):
            request.update(window=validate_patch_window(window), surround=validate_patch_rgb(surround))
        eye = self.eye if eye is None else validate_eye(eye)
        if eye != "both":
            request["eye"] = eye
        self._request(request, f"patch {request['rgb']}" + ("" if eye == "both" else f" to the {eye} eye"))

    def target(self, eye: str | None = None) -> None:
        """Show the centring target (rings and a cross; ``vr-workbench-patch/1``'s ``target``) in
        :attr:`eye` (or ``eye``); return once the frame showing it has been submitted."""
        eye = self.eye if eye is None else validate_eye(eye)
        self._request({"cmd": "target", **({"eye": eye} if eye != "both" else {})}, "the centring target")

    def close(self) -> None:
        """Give the page back to the scene (idempotent); stop the server if this display started it."""
        if self._closed:
            return
        self._closed = True
        try:
            self.server.attach_patches(None)
        finally:
            if self.own_server:
                time.sleep(0.05)  # let the page hear that the measurement is over
                self.server.close()

    def describe(self) -> str:
        """What shows the patches, for the journal header (stable across runs of the same headset)."""
        return f"{self.page.display or 'WebXR page'} via {self.where}"

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def parse_address(rest: str | None) -> tuple:
    """``(host, port)`` from what follows ``webxr:`` (``None``: loopback, the default port).

    Raises
    ------
    ValueError
        Saying what is wrong.
    """
    if rest is None:
        return "127.0.0.1", DEFAULT_PORT
    host, _, port = rest.rpartition(":")
    if not port.isdigit() or not 0 <= int(port) < 65536:
        raise ValueError(f"port {port!r} must be a number 0..65535 (0: a free one, printed)")
    return (host.strip("[]") or "127.0.0.1"), int(port)


def open_display(stack, address: tuple, eye: str = "both", *, timeout_s: float = 10.0,
                 page_timeout_s: float = DEFAULT_PAGE_TIMEOUT_S) -> WebXRPatchDisplay:
    """``measure --display webxr``: serve the page at ``address``, wait for it in VR; closed with ``stack``."""
    host, port = address
    return stack.enter_context(WebXRPatchDisplay.serve(port, host=host, eye=eye, timeout_s=timeout_s,
                                                       page_timeout_s=page_timeout_s))
