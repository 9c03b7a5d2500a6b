"""Fixtures of the measurement tests: a scripted meter measuring a simulated headset."""

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import pytest

from instruments.cs2000 import MeasurementCancelled
from instruments.headset import WAVELENGTHS_NM, SimulatedHeadset, radiance_to_XYZ
from instruments.patch_display import SimulatedPatchDisplay


@dataclass(frozen=True)
class FakeIdentity:
    name: str = "FAKE"
    model: str = "fake meter"
    serial: str = "0001"


class ScriptedMeter:
    """Measures what the headset shows, noiselessly; raises ``errors[n]`` on the n-th call (from 1)."""

    def __init__(self, headset, errors=None, serial="0001"):
        self.headset = headset
        self.errors = dict(errors or {})
        self.calls = 0
        self.serial = serial

    def identify(self):
        return FakeIdentity(serial=self.serial)

    def measure(self, progress=None, cancel=None):
        self.calls += 1
        if cancel is not None and cancel.is_set():
            raise MeasurementCancelled("the start (nothing was sent)")
        if self.calls in self.errors:
            raise self.errors[self.calls]
        radiance = self.headset.current_radiance()
        XYZ = radiance_to_XYZ(radiance)
        if progress is not None:
            progress(0.0, 2.0)
        total = XYZ.sum()
        xy = XYZ[:2] / total if total > 0 else np.full(2, np.nan)
        return SimpleNamespace(wavelengths=WAVELENGTHS_NM, radiance=radiance, XYZ=XYZ, Lv=XYZ[1], xy=xy,
                               integration_s=0.5, nd_used=False)


class RecordingDisplay(SimulatedPatchDisplay):
    """A simulated display that remembers what it showed and can fail on the n-th patch."""

    def __init__(self, headset, fail_on=None, error=None):
        super().__init__(headset)
        self.shown = []
        self.fail_on, self.error = fail_on, error

    def show(self, rgb_dac):
        if self.fail_on is not None and len(self.shown) + 1 == self.fail_on:
            raise self.error
        super().show(rgb_dac)
        self.shown.append(list(rgb_dac))


@pytest.fixture
def headset():
    return SimulatedHeadset({"black-offset": 0.004})


@pytest.fixture
def meter(headset):
    return ScriptedMeter(headset)


@pytest.fixture
def display(headset):
    return RecordingDisplay(headset)
