"""Stand-ins for the seed authors' engines: the engine side of their Unity and Unreal conventions.

What the authors' MATLAB (``src/ConnectionUnity.m``, ``src/ConnectionUnreal.m``
of github.com/rkl-gilro/ColorCharacterization) talks to, byte for byte:

:class:`UnityRgbTextStandin`
    Listens; for each connection reads until the client closes it, parses
    the bare text ``R,G,B`` (decimal integers 0..255, nothing else: no
    terminator, no spaces), shows the patch ``show_delay_s`` later (an
    engine shows it on a later frame), and answers nothing.
:class:`UnrealValueShotStandin`
    Holds one connection; reads ``Value:r,g,b`` messages (channels in 0..1,
    no terminator: a message ends where the next begins or where the client
    pauses), shows the patch ``shot_delay_s`` later and answers ``SHOT``
    (no terminator); with ``answer_from_send=2`` the first send of each new
    value is lost (neither shown nor answered), so only the client's re-send
    gets the patch shown. ``DONE:0`` is recorded.

Each keeps :attr:`shown`, ``(time.monotonic(), [r, g, b])`` of every patch it
showed, :attr:`showing`, the patch on its panel now, :attr:`messages`, the
raw bytes received, and :attr:`errors`, what it could not parse.

:func:`engine_drives_simulation` couples a stand-in to ``measure --simulate``:
the simulated CS-2000 then measures the simulated headset as the **engine**
drives it (the client's own mirror to the headset is dropped), and every
measurement is logged with the patch the engine was showing when the
instrument read it. A patch shown too late, or a wrong one, gives a wrong
XYZ and a wrong log entry.
"""

from __future__ import annotations

import re
import socket
import threading
import time
from dataclasses import dataclass, field

__all__ = ["UnityRgbTextStandin", "UnrealValueShotStandin", "EngineCoupling", "engine_drives_simulation"]

_RGB_TEXT = re.compile(rb"^(\d{1,3}),(\d{1,3}),(\d{1,3})$")
_NUMBER = rb"(0|1|0\.\d+|1\.0*)"
_VALUE = re.compile(rb"^Value:" + _NUMBER + rb"," + _NUMBER + rb"," + _NUMBER + rb"$")
_QUIET_S = 0.02  # a value-shot message without terminator ends when the client pauses this long


class _Standin:
    """What both stand-ins share: a listening socket, a log of shown patches, a panel state."""

    def __init__(self, on_show=None, port: int = 0):
        self.on_show = on_show
        self.shown: list = []
        self.messages: list = []
        self.errors: list = []
        self._showing = [0, 0, 0]
        self._lock = threading.Lock()
        self._listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._listener.bind(("127.0.0.1", port))
        self._listener.listen(8)
        self._address = self._listener.getsockname()[:2]
        self._listener.settimeout(0.05)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True, name=type(self).__name__)

    @property
    def address(self) -> tuple:
        return self._address

    @property
    def showing(self) -> list:
        """The patch on the engine's panel now (black before the first)."""
        with self._lock:
            return list(self._showing)

    def _present(self, rgb: list) -> None:
        with self._lock:
            self._showing = list(rgb)
            self.shown.append((time.monotonic(), list(rgb)))
        if self.on_show is not None:
            self.on_show(list(rgb))

    def start(self):
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self._listener.close()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()

    def _accept(self):
        while not self._stop.is_set():
            try:
                return self._listener.accept()[0]
            except socket.timeout:
                continue
        return None


class UnityRgbTextStandin(_Standin):
    """The authors' Unity engine side: ``R,G,B`` per connection, shown ``show_delay_s`` later, no reply."""

    def __init__(self, on_show=None, show_delay_s: float = 0.0, port: int = 0):
        super().__init__(on_show, port)
        self.show_delay_s = float(show_delay_s)
        self._timers: list = []

    def _serve(self) -> None:
        while (connection := self._accept()) is not None:
            with connection:
                connection.settimeout(2.0)
                data = bytearray()
                try:
                    while chunk := connection.recv(4096):  # until the client closes
                        data += chunk
                except OSError as error:
                    self.errors.append(f"read failed: {error}")
                    continue
            self.messages.append(bytes(data))
            match = _RGB_TEXT.match(bytes(data))
            if not match or any(int(v) > 255 for v in match.groups()):
                self.errors.append(f"not R,G,B: {bytes(data)!r}")
                continue
            rgb = [int(v) for v in match.groups()]
            if self.show_delay_s > 0:
                timer = threading.Timer(self.show_delay_s, self._present, (rgb,))
                self._timers.append(timer)
                timer.start()
            else:
                self._present(rgb)

    def close(self) -> None:
        super().close()
        for timer in self._timers:
            timer.join(timeout=5)


class UnrealValueShotStandin(_Standin):
    """The authors' Unreal engine side: ``Value:r,g,b`` on one connection, ``SHOT`` once shown.

    Parameters
    ----------
    on_show : callable, optional
        ``on_show([r, g, b])`` when a patch is shown.
    shot_delay_s : float
        Seconds between reading a value and showing it (then ``SHOT``).
    answer_from_send : int
        1: every send is shown and answered; 2: the first send of each new
        value is lost, the second (the client's re-send) is shown and answered.
    """

    def __init__(self, on_show=None, shot_delay_s: float = 0.0, answer_from_send: int = 1, port: int = 0):
        super().__init__(on_show, port)
        self.shot_delay_s = float(shot_delay_s)
        self.answer_from_send = int(answer_from_send)
        self.done = False
        self.connections = 0
        self._sends_of_value: dict = {}
        self._last_value = None

    def _serve(self) -> None:
        while (connection := self._accept()) is not None:
            self.connections += 1
            with connection:
                self._converse(connection)

    def _converse(self, connection) -> None:
        connection.settimeout(_QUIET_S)
        pending = bytearray()
        while not self._stop.is_set():
            try:
                chunk = connection.recv(4096)
            except socket.timeout:
                if pending:
                    self._messages(bytes(pending), connection)
                    pending.clear()
                continue
            except OSError:
                return
            if not chunk:
                break
            pending += chunk
        try:  # stopped: what the client sent last (DONE:0) is still read
            while chunk := connection.recv(4096):
                pending += chunk
        except OSError:
            pass
        if pending:
            self._messages(bytes(pending), connection)

    def _messages(self, data: bytes, connection) -> None:
        """Split what arrived into messages (each starts with ``Value:`` or ``DONE:``) and act on each."""
        for message in re.split(rb"(?=Value:|DONE:)", data):
            if not message:
                continue
            self.messages.append(message)
            if message == b"DONE:0":
                self.done = True
                continue
            match = _VALUE.match(message)
            if not match:
                self.errors.append(f"not Value:r,g,b: {message!r}")
                continue
            rgb = [round(float(v) * 255) for v in match.groups()]
            if message != self._last_value:
                self._sends_of_value = {}
                self._last_value = message
            sends = self._sends_of_value[message] = self._sends_of_value.get(message, 0) + 1
            if sends < self.answer_from_send:
                continue  # lost: neither shown nor answered
            time.sleep(self.shot_delay_s)
            self._present(rgb)
            try:
                connection.sendall(b"SHOT")
            except OSError:
                return


@dataclass
class EngineCoupling:
    """What :func:`engine_drives_simulation` logged.

    Attributes
    ----------
    measured : list
        For each measurement the simulated instrument made, the patch the
        engine was showing when it read the headset.
    mirrored : list
        What the client itself sent to the simulated headset (dropped).
    simulations : list
        The simulated instruments opened.
    """

    measured: list = field(default_factory=list)
    mirrored: list = field(default_factory=list)
    simulations: list = field(default_factory=list)


class _EngineDrivenHeadset:
    """The simulated headset as the client sees it: its ``show`` (the client's mirror) is dropped."""

    def __init__(self, headset, coupling: EngineCoupling):
        self._headset, self._coupling = headset, coupling

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        self._coupling.mirrored.append([int(v) for v in rgb_dac])

    def __getattr__(self, name):
        return getattr(self._headset, name)


def engine_drives_simulation(monkeypatch, standin) -> EngineCoupling:
    """Make ``measure --simulate`` measure the simulated headset as ``standin`` drives it.

    The stand-in's shown patches go to the simulated headset the emulator
    measures; the client's mirror of each patch to that headset is dropped;
    every reading of the headset by the emulator logs ``standin.showing``.
    """
    import workbench.cli.measure as measure_cli
    from workbench.measurement.simulation import SimulatedInstrument, open_simulated_instrument

    coupling = EngineCoupling()

    def opened(*args, **kwargs):
        simulation = open_simulated_instrument(*args, **kwargs)
        headset = simulation.headset
        read = headset.current_radiance

        def current_radiance():
            coupling.measured.append(standin.showing)
            return read()

        headset.current_radiance = current_radiance  # the emulator's radiance source calls it
        standin.on_show = headset.show
        coupling.simulations.append(simulation)
        return SimulatedInstrument(_EngineDrivenHeadset(headset, coupling), simulation.emulator,
                                   simulation.server, simulation.clock)

    monkeypatch.setattr(measure_cli, "open_simulated_instrument", opened)
    return coupling
