"""External tools of the conformance tests: found, or the test skips naming the Debian package."""

import shutil

import pytest

DEBIAN_PACKAGES = {"glslangValidator": "glslang-tools", "spirv-val": "spirv-tools",
                   "spirv-cross": "spirv-cross", "mcs": "mono-mcs"}


def need_tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        pytest.skip(f"{name} not found: install the Debian package {DEBIAN_PACKAGES[name]} "
                    "(make test installs it as root)")
    return path
