"""A headset's browser as a VR runtime: the WebXR page, its server and the ``webxr`` patch display.

- :mod:`workbench.vr.server`: :class:`~workbench.vr.server.WebXRServer`, HTTP +
  WebSocket on its own thread (aiohttp), serving ``static/`` and the bundle;
- :mod:`workbench.vr.patch_display`: :class:`~workbench.vr.patch_display.WebXRPatchDisplay`,
  ``measure --display webxr[:PORT]``;
- :mod:`workbench.vr.security`: loopback, the URL token, same-origin WebSockets,
  the self-signed certificate;
- :mod:`workbench.vr.bundle_files`: what the page may read of a bundle;
- :mod:`workbench.vr.scene_cubes`: the lightbooth as one hyperspectral cube for ``export --cube``;
- :mod:`workbench.vr.terminal_qr`: the URL as a QR code.

The page (``static/``) is plain WebGL 2 with no build step; ``docs/vr/webxr.md``
is the user's guide. Nothing here imports Qt.
"""

__all__ = ["WebXRServer", "WebXRPatchDisplay"]


def __getattr__(name):
    if name == "WebXRServer":
        from workbench.vr.server import WebXRServer
        return WebXRServer
    if name == "WebXRPatchDisplay":
        from workbench.vr.patch_display import WebXRPatchDisplay
        return WebXRPatchDisplay
    raise AttributeError(name)
