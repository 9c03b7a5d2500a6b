"""The WebXR server: one static page, the bundle's files, and a WebSocket to the page.

:class:`WebXRServer` runs an aiohttp application on its own thread (its own
asyncio loop), so that the measurement (a plain blocking loop), the GUI and the
``vr serve`` command all drive it the same way through thread-safe methods:

- ``GET <base>`` — the page (``workbench/vr/static/index.html``); ``<base>``
  is ``/`` on loopback and ``/<token>/`` elsewhere (:mod:`workbench.vr.security`);
- ``GET <base>static/...`` — the page's scripts and the vendored modules;
- ``GET <base>scene.json`` — the bundle's lights and the lightbooth's layout;
- ``GET <base>bundle/<file>`` — the bundle files the page reads (nothing else);
- ``GET <base>ws`` — the WebSocket (same origin only).

Why aiohttp: HTTP and WebSocket in one asyncio server with TLS, heartbeats and
per-message size limits, a library that is well kept and already a dependency
of the scientific Python stack; ``websockets`` alone would need a second
server for the static files.

The WebSocket (``vr-workbench-webxr/1``), one JSON object per message:

page → server
    ``{"event": "hello", "page": "vr-workbench-webxr/1", "user_agent": ..., "xr": ...}`` first;
    ``{"event": "state", "immersive": bool, "views": n, "eyes": [...], "framebuffer": [w, h], "display": ...}``
    whenever the XR session starts or ends; ``{"event": "scene", "source": id, "level": 1|2}`` when
    the user switches in the headset; replies ``{"ok": true|false, "id": N, ...}`` to requests.
server → page
    ``{"event": "welcome", ...}`` or ``{"event": "refused", "reason": ...}`` (then closed);
    ``{"event": "scene", "source": id, "level": 1|2}``; ``{"event": "patches", "client": str | null}``
    (a measurement is waiting for the page, or is over); requests ``{"cmd": "show", "id": N, "rgb": [...],
    ["window": w, "surround": [...]], ["eye": "left"|"right"]}`` and ``{"cmd": "target", "id": N, ["eye"]}``,
    answered once the XR frame showing them has been submitted (``vr-workbench-patch/1``'s fields and rules).

One page at a time: while a page is connected, a second one is told why it is
refused (the first page's address and browser) and closed.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import json
import logging
import threading
import time
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

from workbench import __version__
from workbench.errors import InputError, WorkbenchError
from workbench.vr.bundle_files import SceneBundle
from workbench.vr.security import Access, Certificate, is_loopback, lan_address, self_signed_certificate

__all__ = [
    "PAGE_PROTOCOL",
    "DEFAULT_PORT",
    "PageState",
    "ServerStatus",
    "PageGone",
    "WebXRServer",
    "static_folder",
]

_LOG = logging.getLogger(__name__)

PAGE_PROTOCOL = "vr-workbench-webxr/1"
"""Name and version of the page ↔ server WebSocket messages (module doc)."""

DEFAULT_PORT = 47900
"""Default TCP port of the server (the TCP patch protocol's examples use 47800)."""

_HELLO_TIMEOUT_S = 10.0
_MAX_MESSAGE_BYTES = 64 * 1024
_HEARTBEAT_S = 15.0
_NO_CACHE = {"Cache-Control": "no-store"}


def static_folder() -> Path:
    """The page's files, installed with the package."""
    return Path(str(resources.files("workbench.vr").joinpath("static")))


class PageGone(WorkbenchError):
    """The page that was showing the patches went away (closed, reloaded, disconnected)."""


@dataclass(frozen=True)
class PageState:
    """The connected page, as it last described itself.

    Attributes
    ----------
    serial : int
        Which connection (counts from 1 over the server's life; 0: none yet).
    connected : bool
    address : str
        ``HOST:PORT`` the page connected from.
    user_agent : str
    immersive : bool
        Whether an immersive XR session is running (patches are shown only then).
    views : int
        The XR session's views (2 in a headset).
    eyes : tuple of str
        Their ``XRView.eye``.
    framebuffer : tuple of int
        The XR framebuffer's width and height.
    display : str
        What the page says it shows on (for the journal header).
    """

    serial: int = 0
    connected: bool = False
    address: str = ""
    user_agent: str = ""
    immersive: bool = False
    views: int = 0
    eyes: tuple = ()
    framebuffer: tuple = ()
    display: str = ""

    def describe(self) -> str:
        """One line naming the page: its address and browser."""
        if not self.serial:
            return "no page"
        return f"the page at {self.address} ({_short_agent(self.user_agent)})"


@dataclass(frozen=True)
class ServerStatus:
    """Everything a view of the server shows (what :meth:`WebXRServer.add_listener` callbacks get).

    Attributes
    ----------
    url : str
    page : PageState
    scene : dict
        ``{"source": id, "level": 1|2}`` (source ``None`` without a bundle).
    patches : str or None
        The measurement waiting for or using the page, or ``None``.
    """

    url: str
    page: PageState
    scene: dict = field(default_factory=dict)
    patches: str | None = None

    def connection(self) -> str:
        """The connection state in words: waiting / connected (not in VR) / in VR."""
        if not self.page.connected:
            return "waiting for the headset's browser"
        where = self.page.describe()
        return f"{where}: in VR" if self.page.immersive else f"{where}: connected, not in VR (press Enter VR)"


def _short_agent(user_agent: str) -> str:
    """The browser's product tokens that say what it runs on (OculusBrowser, Chrome, ...)."""
    tokens = [t for t in user_agent.split() if "/" in t and not t.startswith(("Mozilla/", "AppleWebKit/",
                                                                                "Safari/", "KHTML"))]
    return " ".join(tokens[:3]) or user_agent[:60] or "unknown browser"


@dataclass
class _Page:
    serial: int
    socket: object
    state: PageState
    pending: dict = field(default_factory=dict)
    next_id: int = 1


class WebXRServer:
    """HTTP + WebSocket server of the WebXR page (module doc).

    Parameters
    ----------
    host : str
        Address to listen on; loopback by default. Another interface requires
        the token (made here) and, for WebXR, TLS (``tls``).
    port : int
        TCP port (0: a free one).
    bundle : path-like or SceneBundle, optional
        The runtime bundle whose lightbooth the page shows.
    tls : bool, optional
        Serve HTTPS with a self-signed certificate; default: when ``host`` is
        not loopback (WebXR needs a secure context there).
    token : str, optional
        The token for a non-loopback host (default: a random one).
    certificate_folder : path-like, optional
        Where the self-signed certificate is kept (default: the user's configuration folder).

    Examples
    --------
    >>> with WebXRServer(port=0) as server:        # doctest: +SKIP
    ...     print(server.url)
    ...     server.wait_for_page(timeout_s=600)
    """

    def __init__(self, *, host: str = "127.0.0.1", port: int = DEFAULT_PORT, bundle=None,
                 tls: bool | None = None, token: str | None = None, certificate_folder=None):
        if not isinstance(port, int) or not 0 <= port < 65536:
            raise InputError(f"--port {port!r} must be 0..65535 (0: a free port)")
        self.bundle = bundle if isinstance(bundle, SceneBundle) or bundle is None else SceneBundle.open(bundle)
        self.host = host
        self.tls = (not is_loopback(host)) if tls is None else bool(tls)
        self._access = Access.for_host(host, port, token)
        self._certificate_folder = certificate_folder
        self.certificate: Certificate | None = None
        self._requested_port = port
        self.port = port
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._runner = None
        self._page: _Page | None = None
        self._serial = 0
        self._last_page = PageState()
        self._changed = threading.Condition()
        self._listeners = []
        self._patches: str | None = None
        first = self.bundle.light_ids()[0] if self.bundle else None
        self._scene = {"source": first, "level": 2 if self.bundle else 1}
        self._closed = False

    # ------------------------------------------------------------------ life
    def start(self) -> "WebXRServer":
        """Listen (on its own thread); return once it does.

        Raises
        ------
        InputError
            When the port cannot be bound (in use, or not allowed).
        """
        if self._thread is not None:
            return self
        ssl_context = None
        if self.tls:
            names = ["localhost", "127.0.0.1"]
            names += [lan_address()] if self.host in ("0.0.0.0", "::", "") else [self.host.strip("[]")]
            self.certificate = self_signed_certificate(names, self._certificate_folder)
            ssl_context = self.certificate.ssl_context()
        self._loop = asyncio.new_event_loop()
        started = concurrent.futures.Future()
        self._thread = threading.Thread(target=self._serve, args=(started, ssl_context),
                                        name=f"webxr-server:{self._requested_port}", daemon=True)
        self._thread.start()
        try:
            self.port = started.result(timeout=30)
        except OSError as error:
            self._thread.join(timeout=5)
            self._thread = None
            raise InputError(f"cannot listen on {self.host}:{self._requested_port} ({error.strerror or error}); "
                             "another program (an earlier `vr serve` or measure --display webxr?) may use "
                             "it: stop it, or choose another port") from None
        self._access = replace(self._access, port=self.port)
        _LOG.info("WebXR server listening at %s", self.url)
        return self

    def _serve(self, started: concurrent.futures.Future, ssl_context) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            port = self._loop.run_until_complete(self._start_site(ssl_context))
        except BaseException as error:  # noqa: BLE001 - handed to the starting thread
            started.set_exception(error)
            self._loop.close()
            return
        started.set_result(port)
        try:
            self._loop.run_forever()
        finally:
            self._loop.run_until_complete(self._stop_site())
            self._loop.close()

    async def _start_site(self, ssl_context) -> int:
        from aiohttp import web

        app = web.Application(middlewares=[self._guard], client_max_size=_MAX_MESSAGE_BYTES)
        base = self._access.base_path
        app.router.add_get(base, self._index)
        if base != "/":
            app.router.add_get(base.rstrip("/"), self._to_base)
        app.router.add_get(base + "scene.json", self._scene_json)
        app.router.add_get(base + "bundle/{path:.+}", self._bundle_file)
        app.router.add_get(base + "ws", self._websocket)
        app.router.add_static(base + "static/", static_folder(), follow_symlinks=False,
                              append_version=False)
        self._runner = web.AppRunner(app, access_log=None, handle_signals=False, shutdown_timeout=1.0)
        await self._runner.setup()
        site = web.TCPSite(self._runner, self.host, self._requested_port, ssl_context=ssl_context)
        try:
            await site.start()
        except BaseException:
            await self._runner.cleanup()
            raise
        sockets = site._server.sockets if site._server else []  # the port bound, for port 0
        return sockets[0].getsockname()[1] if sockets else self._requested_port

    async def _stop_site(self) -> None:
        page = self._page
        if page is not None:
            await page.socket.close(code=1001, message=b"the workbench's server is stopping")
        if self._runner is not None:
            await self._runner.cleanup()

    def close(self) -> None:
        """Stop serving (idempotent): the page is told the server stopped."""
        if self._closed:
            return
        self._closed = True
        if self._thread is None:
            return
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=10)
        self._thread = None

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()

    # ---------------------------------------------------------------- where
    @property
    def url(self) -> str:
        """The URL to open in the headset's browser (token included)."""
        scheme = "https" if self.tls else "http"
        host = self.host
        if host in ("0.0.0.0", "::", ""):
            host = lan_address()
        elif host == "::1" or ":" in host:
            host = f"[{host.strip('[]')}]"
        return f"{scheme}://{host}:{self.port}{self._access.base_path}"

    @property
    def token(self) -> str | None:
        """The URL's token (``None`` on loopback)."""
        return self._access.token

    # ---------------------------------------------------------------- state
    def status(self) -> ServerStatus:
        """The server's state now (thread-safe)."""
        with self._changed:
            return ServerStatus(self.url, self._last_page, dict(self._scene), self._patches)

    @property
    def page(self) -> PageState:
        """The page as it last described itself (``connected`` False once it has gone)."""
        with self._changed:
            return self._last_page

    def add_listener(self, callback) -> None:
        """Call ``callback(ServerStatus)`` on every change (page, XR session, scene, measurement).

        Called on the server's thread: a GUI must hand it to its own thread (a queued signal).
        """
        self._listeners.append(callback)

    def _changed_now(self, page: PageState | None = None) -> None:
        with self._changed:
            if page is not None:
                self._last_page = page
            self._changed.notify_all()
        status = self.status()
        for callback in list(self._listeners):
            try:
                callback(status)
            except Exception:  # noqa: BLE001 - a listener's bug must not stop the server
                _LOG.exception("WebXR server listener failed")

    def wait_for_page(self, timeout_s: float, *, immersive: bool = True, cancel=None) -> PageState:
        """Wait until a page is connected (and in an immersive session, by default).

        Raises
        ------
        TimeoutError
            When none is within ``timeout_s`` seconds (the message says what was missing).
        """
        deadline = time.monotonic() + timeout_s
        with self._changed:
            while True:
                page = self._last_page
                if page.connected and (page.immersive or not immersive):
                    return page
                remaining = deadline - time.monotonic()
                if cancel is not None and cancel.is_set():
                    raise TimeoutError(f"stopped waiting for a page at {self.url} (cancelled)")
                if remaining <= 0:
                    if page.connected:
                        raise TimeoutError(f"{page.describe()} is connected but did not enter VR within "
                                           f"{timeout_s:g} s (press Enter VR on the page)")
                    raise TimeoutError(f"no page opened {self.url} within {timeout_s:g} s")
                self._changed.wait(min(remaining, 0.5))

    # ---------------------------------------------------------------- scene
    def set_scene(self, source: str | None = None, level: int | None = None) -> dict:
        """Show ``source`` (a bundle light id) at ``level`` (1 or 2) on the page; return the scene.

        Raises
        ------
        InputError
            For a source the bundle has no light for, or a level other than 1 or 2.
        """
        if self.bundle is None:
            raise InputError("the WebXR server has no bundle, so no scene to switch; start it with --bundle DIR")
        scene = dict(self._scene)
        if source is not None:
            if source not in self.bundle.light_ids():
                raise InputError(f"source {source!r} is not in the bundle {self.bundle.folder}; it has "
                                 f"{', '.join(self.bundle.light_ids())} (export it with --lights)")
            scene["source"] = source
        if level is not None:
            if level not in (1, 2):
                raise InputError(f"level {level!r} must be 1 or 2")
            scene["level"] = int(level)
        self._scene = scene
        self._post({"event": "scene", **scene})
        self._changed_now()
        return dict(scene)

    def _post(self, message: dict) -> None:
        """Send ``message`` to the page, if there is one (from any thread; fire and forget)."""
        if self._loop is None or self._thread is None:
            return

        async def send():
            page = self._page
            if page is not None and not page.socket.closed:
                await page.socket.send_str(json.dumps(message))

        asyncio.run_coroutine_threadsafe(send(), self._loop)

    # -------------------------------------------------------------- patches
    def attach_patches(self, client: str | None) -> None:
        """Tell the page a measurement (``client``) is waiting to show patches, or (``None``) that it is over."""
        self._patches = client
        self._post({"event": "patches", "client": client})
        self._changed_now()

    def request(self, message: dict, timeout_s: float, *, page_serial: int) -> tuple[dict, int]:
        """Send a request (``cmd``...) to page ``page_serial`` and wait for its reply.

        Returns
        -------
        (reply, id)
            The page's reply object and the request's id.

        Raises
        ------
        PageGone
            That page is no longer connected, or goes away before replying.
        TimeoutError
            No reply within ``timeout_s``.
        """
        if self._loop is None or self._thread is None:
            raise PageGone("the WebXR server is not running")
        future = asyncio.run_coroutine_threadsafe(self._request(message, page_serial), self._loop)
        try:
            return future.result(timeout_s)
        except concurrent.futures.TimeoutError:
            future.cancel()
            raise TimeoutError(f"no reply within {timeout_s:g} s") from None

    async def _request(self, message: dict, page_serial: int) -> tuple[dict, int]:
        page = self._page
        if page is None or page.serial != page_serial:
            raise PageGone(f"{self._described(page_serial)} went away")
        request_id = page.next_id
        page.next_id += 1
        reply = asyncio.get_running_loop().create_future()
        page.pending[request_id] = reply
        try:
            await page.socket.send_str(json.dumps({**message, "id": request_id}))
            return await reply, request_id
        except ConnectionError as error:
            raise PageGone(f"{self._described(page_serial)} went away ({error})") from None
        finally:
            page.pending.pop(request_id, None)

    def _described(self, serial: int) -> str:
        page = self._last_page
        return page.describe() if page.serial == serial else f"the page (connection {serial})"

    # ------------------------------------------------------------- handlers
    def _refuse(self, what: str):
        from aiohttp import web

        return web.Response(status=403, text=self._access.refusal(what) + "\n", headers=_NO_CACHE)

    async def _guard_impl(self, request, handler):
        if not self._access.host_allowed(request.headers.get("Host")):
            return self._refuse(f"the Host {request.headers.get('Host')!r} is not this server's loopback "
                                "address (a page elsewhere may not reach it)")
        if not self._access.path_allowed(request.path):
            return self._refuse("this server serves only under its token, and the request has none "
                                "or the wrong one")
        response = await handler(request)
        return response

    @property
    def _guard(self):
        from aiohttp import web

        @web.middleware
        async def guard(request, handler):
            return await self._guard_impl(request, handler)
        return guard

    async def _to_base(self, request):
        from aiohttp import web

        raise web.HTTPFound(self._access.base_path)

    async def _index(self, request):
        from aiohttp import web

        return web.FileResponse(static_folder() / "index.html", headers=_NO_CACHE)

    async def _scene_json(self, request):
        from aiohttp import web

        body = {"page": PAGE_PROTOCOL, "server": f"vr-workbench {__version__}",
                "bundle": self.bundle.describe() if self.bundle else None, "scene": dict(self._scene)}
        return web.json_response(body, headers=_NO_CACHE)

    async def _bundle_file(self, request):
        from aiohttp import web

        path = self.bundle.file(request.match_info["path"]) if self.bundle else None
        if path is None:
            raise web.HTTPNotFound(text="not a bundle file the page reads\n")
        return web.FileResponse(path, headers=_NO_CACHE)

    async def _websocket(self, request):
        from aiohttp import WSMsgType, web

        if not self._access.origin_allowed(request.headers.get("Origin"), request.headers.get("Host")):
            return self._refuse(f"a WebSocket from the origin {request.headers.get('Origin')!r}, not this "
                                "server's own page")
        socket = web.WebSocketResponse(heartbeat=_HEARTBEAT_S, max_msg_size=_MAX_MESSAGE_BYTES)
        await socket.prepare(request)
        peer = request.transport.get_extra_info("peername") if request.transport else None
        address = f"{peer[0]}:{peer[1]}" if peer else "?"
        try:
            first = await socket.receive(timeout=_HELLO_TIMEOUT_S)
            hello = json.loads(first.data) if first.type == WSMsgType.TEXT else {}
        except (asyncio.TimeoutError, ValueError, TypeError):
            hello = {}
        if not isinstance(hello, dict) or hello.get("event") != "hello" or hello.get("page") != PAGE_PROTOCOL:
            await socket.send_str(json.dumps({"event": "refused", "reason": (
                f"this server speaks {PAGE_PROTOCOL}; reload the page from {self.url}")}))
            await socket.close()
            return socket
        agent = str(hello.get("user_agent", ""))[:300]
        current = self._page
        if current is not None and not current.socket.closed:
            reason = (f"busy: this server is showing its page to {current.state.address} "
                      f"({_short_agent(current.state.user_agent)}) — one page at a time; close that page "
                      "(or its tab) first, then reload this one")
            _LOG.info("refused a second page from %s: %s", address, reason)
            await socket.send_str(json.dumps({"event": "refused", "reason": reason}))
            await socket.close()
            return socket
        self._serial += 1
        page = _Page(self._serial, socket, PageState(serial=self._serial, connected=True, address=address,
                                                     user_agent=agent))
        self._page = page
        self._changed_now(page.state)
        await socket.send_str(json.dumps({
            "event": "welcome", "page": PAGE_PROTOCOL, "server": f"vr-workbench {__version__}",
            "connection": page.serial, "scene": dict(self._scene), "patches": self._patches}))
        try:
            async for message in socket:
                if message.type != WSMsgType.TEXT:
                    continue
                self._on_message(page, message.data)
        finally:
            if self._page is page:
                self._page = None
            for reply in page.pending.values():
                if not reply.done():
                    reply.set_exception(PageGone(f"{page.state.describe()} went away"))
            self._changed_now(replace(page.state, connected=False, immersive=False))
            _LOG.info("page %s went away", address)
        return socket

    def _on_message(self, page: _Page, text: str) -> None:
        try:
            message = json.loads(text)
        except ValueError:
            _LOG.warning("page %s sent a message that is not JSON: %.80r", page.state.address, text)
            return
        if not isinstance(message, dict):
            return
        if "ok" in message:
            reply = page.pending.get(message.get("id"))
            if reply is not None and not reply.done():
                reply.set_result(message)
            return
        event = message.get("event")
        if event == "state":
            eyes = message.get("eyes") if isinstance(message.get("eyes"), list) else []
            size = message.get("framebuffer") if isinstance(message.get("framebuffer"), list) else []
            page.state = replace(page.state, immersive=bool(message.get("immersive")),
                                 views=int(message.get("views") or 0), eyes=tuple(str(e) for e in eyes),
                                 framebuffer=tuple(int(v) for v in size[:2]),
                                 display=str(message.get("display", ""))[:200])
            self._changed_now(page.state)
        elif event == "scene" and self.bundle is not None:
            source, level = message.get("source"), message.get("level")
            if source in self.bundle.light_ids() and level in (1, 2):
                self._scene = {"source": source, "level": level}
                self._changed_now()
