#!/usr/bin/env bash
# Check (and, as root, install) the Debian packages the workbench needs beyond
# a fresh machine: Python's venv module, what Qt, the 3D view and the
# headless GUI tests need (design notes §8), ArgyllCMS (the peer profiler the
# diagnosis is compared with) and the shader/C# compilers the runtime-bundle
# conformance tests run (glslang, SPIRV-Tools, SPIRV-Cross, mono's mcs). Never fails the build for a
# missing package when not root: it says what is missing and how to install it.
set -u
PYTHON=${PYTHON:-python3}
packages="xvfb xauth libxcb-icccm4 libxcb-keysyms1 libxcb-cursor0 libxkbcommon-x11-0 \
libgl1 libegl1 libgl1-mesa-dri libegl-mesa0 libfontconfig1 libdbus-1-3 \
argyll glslang-tools spirv-tools spirv-cross mono-mcs mono-runtime chromium"
if ! "$PYTHON" -c 'import venv, ensurepip' >/dev/null 2>&1; then
    version=$("$PYTHON" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")' 2>/dev/null)
    packages="python${version}-venv python3-venv $packages"
fi
if ! command -v dpkg-query >/dev/null 2>&1; then
    echo "note: not a Debian system; make sure Qt's xcb libraries, Mesa GL/EGL and Xvfb are installed" >&2
    exit 0
fi
missing=""
for package in $packages; do
    if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $package"
    fi
done
[ -z "$missing" ] && exit 0
if [ "$(id -u)" = "0" ]; then
    echo "installing system packages:$missing" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq && apt-get install -y -qq --no-install-recommends $missing >/dev/null \
        || { echo "error: apt-get could not install:$missing" >&2; exit 1; }
else
    echo "warning: missing system packages:$missing" >&2
    echo "         install them with: sudo apt-get install -y$missing" >&2
    echo "         (without them the GUI tests are skipped and the 3D view stays blank)" >&2
fi
exit 0
