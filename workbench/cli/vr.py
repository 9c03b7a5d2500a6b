"""``vr``: the WebXR page for a headset's browser (``workbench.vr``).

::

    vr-workbench vr serve [--bundle DIR] [--host 127.0.0.1] [--port 47900] [--tls | --no-tls]
                          [--source ID] [--level 1|2]
    vr-workbench vr cube --out DIR
    vr-workbench vr bundle PROFILE --bundle DIR [--lights ID,...]

``serve`` serves the page (and the lightbooth of ``--bundle``) until Ctrl-C,
printing its URL, a QR code for the headset's browser to scan, and every
change of the page's connection. Loopback by default; ``--host`` on another
interface puts a random token in the URL (requests without it get 403) and
serves HTTPS with a self-signed certificate (WebXR needs a secure context).
``cube`` writes the lightbooth (ColorChecker board, Ishihara plate, grey wall)
as the hyperspectral cube ``DIR/lightbooth.npz`` for ``export --cube``;
``bundle`` does both steps: the runtime bundle of a profile with that cube.
Calibration patches go to the page with ``measure --display webxr[:PORT]``.
"""

from __future__ import annotations

import sys
import threading

from workbench.errors import InputError

__all__ = ["register"]


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "vr", help="serve the WebXR page for a headset's browser (patches, colour-managed lightbooth)",
        description="The headset's browser as a VR runtime: a WebXR page that shows the calibration "
                    "patches (measure --display webxr) and the bundle's colour-managed lightbooth.")
    commands = parser.add_subparsers(dest="vr_command", metavar="SUBCOMMAND")
    serve = commands.add_parser("serve", help="serve the page until Ctrl-C; print its URL and a QR code",
                                description="Serve the WebXR page (and the lightbooth of --bundle) until "
                                            "Ctrl-C.")
    serve.add_argument("--bundle", metavar="DIR",
                       help="runtime bundle with the lightbooth cube (vr bundle, or export --cube)")
    serve.add_argument("--host", default="127.0.0.1",
                       help="address to listen on (default 127.0.0.1; another interface adds a token and TLS)")
    serve.add_argument("--port", type=int, default=None, metavar="N", help="TCP port (default 47900; 0: free)")
    tls = serve.add_mutually_exclusive_group()
    tls.add_argument("--tls", dest="tls", action="store_true", default=None,
                     help="serve HTTPS with a self-signed certificate (default off loopback)")
    tls.add_argument("--no-tls", dest="tls", action="store_false", help="serve plain HTTP")
    serve.add_argument("--source", metavar="ID", help="the light to show first (default: the bundle's first)")
    serve.add_argument("--level", type=int, choices=(1, 2), help="colour-management level to show first")
    serve.set_defaults(handler=_serve)
    cube = commands.add_parser("cube", help="write the lightbooth as a hyperspectral cube for export --cube")
    cube.add_argument("--out", required=True, metavar="DIR", help="folder for lightbooth.npz")
    cube.set_defaults(handler=_cube)
    bundle = commands.add_parser("bundle", help="export a profile's runtime bundle with the lightbooth cube")
    bundle.add_argument("profile", help="a .vrprofile.json")
    bundle.add_argument("--bundle", required=True, metavar="DIR", help="output folder (as export --bundle)")
    bundle.add_argument("--lights", metavar="ID,...", help="source ids (default: the profile's lights)")
    bundle.set_defaults(handler=_bundle)
    parser.set_defaults(handler=lambda args: parser.print_help() or 1)


def _cube(args) -> int:
    from workbench.vr.scene_cubes import write_scene_cube

    path = write_scene_cube(args.out)
    print(f"wrote {path}; make a bundle with: python -m workbench export PROFILE --bundle DIR --cube {path}")
    return 0


def _bundle(args) -> int:
    from workbench.export import write_bundle
    from workbench.profile import load_profile
    from workbench.vr.scene_cubes import SCENE_CUBE, scene_cube

    lights = None
    if args.lights:
        lights = [item.strip() for item in args.lights.split(",") if item.strip()]
        if not lights:
            raise InputError(f"--lights {args.lights!r}: give source ids separated by commas")
    profile = load_profile(args.profile)
    summary = write_bundle(profile, args.bundle, light_ids=lights, cubes=[(SCENE_CUBE, scene_cube())])
    cube = summary.cubes[0]
    print(f"bundle {summary.directory}: {len(summary.lights)} light(s); level2/{SCENE_CUBE}: K = "
          f"{cube['components']} + {cube['split']}; serve it with: python -m workbench vr serve "
          f"--bundle {summary.directory}")
    return 0


def _serve(args) -> int:
    from workbench.vr.server import DEFAULT_PORT, WebXRServer
    from workbench.vr.terminal_qr import qr_text

    server = WebXRServer(host=args.host, port=DEFAULT_PORT if args.port is None else args.port,
                         bundle=args.bundle, tls=args.tls)
    if args.source is not None or args.level is not None:
        server.set_scene(args.source, args.level)
    server.start()
    stopped = threading.Event()
    last = {"text": None}

    def report(status) -> None:
        text = status.connection()
        if text != last["text"]:
            last["text"] = text
            print(f"vr serve: {text}", file=sys.stderr, flush=True)

    server.add_listener(report)
    try:
        encoding = (getattr(sys.stdout, "encoding", None) or "ascii").lower()
        print(f"Open {server.url} in the headset's browser (or scan):")
        print(qr_text(server.url, unicode="utf" in encoding))
        if server.certificate is not None:
            print(f"HTTPS with a self-signed certificate: {server.certificate.cert_path}\n"
                  f"  SHA-256 {server.certificate.sha256}\n"
                  "  the browser warns once: check the fingerprint, then proceed (docs/vr/webxr.md)")
        if server.bundle is None:
            print("No --bundle: the page shows no lightbooth (make one: python -m workbench vr bundle "
                  "PROFILE --bundle DIR)")
        else:
            print(f"Lightbooth of {server.bundle.folder}: {', '.join(server.bundle.light_ids())}")
        print("Ctrl-C stops the server.", flush=True)
        while not stopped.wait(0.5):
            pass
    except KeyboardInterrupt:
        print("vr serve: stopped", file=sys.stderr)
    finally:
        server.close()
    return 0
