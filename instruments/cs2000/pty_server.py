"""Serve a :class:`~instruments.cs2000.emulator.CS2000Emulator` on a pseudo-terminal.

:func:`serve_on_pty` opens a pty pair (``os.openpty``, raw mode), and runs a
background thread that feeds what the host writes on the slave side into the
emulator and writes the emulator's replies back, calling
:meth:`~instruments.cs2000.emulator.CS2000Emulator.poll` between reads so
that the unsolicited ``MEAS`` lines go out on time. The real driver opens
``server.port`` (``/dev/pts/N``) by name with pyserial and runs unchanged.

POSIX only (Linux, macOS). The emulator is touched only by the server thread.
"""

from __future__ import annotations

import logging
import os
import select
import threading
import time
import tty

from instruments.cs2000.emulator import CS2000Emulator

__all__ = ["PtyServer", "serve_on_pty"]

logger = logging.getLogger("instruments.cs2000.pty")


class PtyServer:
    """A CS-2000 emulator behind a pseudo-terminal.

    Use :func:`serve_on_pty` to make one. It is a context manager;
    :meth:`close` stops the thread and closes both ends.

    Attributes
    ----------
    port
        Path of the slave device (e.g. ``/dev/pts/4``) for the host to open.
    emulator
        The emulator being served.
    """

    def __init__(self, emulator: CS2000Emulator, poll_interval_s: float = 0.005) -> None:
        if not poll_interval_s > 0:
            raise ValueError(f"poll_interval_s must be positive, got {poll_interval_s!r}")
        self.emulator = emulator
        self._poll_interval_s = float(poll_interval_s)
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.port = os.ttyname(self._slave)
        self._wake_r, self._wake_w = os.pipe()
        self._stop = threading.Event()
        self._vanish_requested = threading.Event()
        self._master_closed = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(
            target=self._run, name=f"cs2000-pty {self.port}", daemon=True
        )
        self._thread.start()
        logger.info("CS-2000 emulator serving on %s", self.port)

    # ------------------------------------------------------------------ control

    @property
    def vanished(self) -> bool:
        """Whether the master side has been closed (the port is gone for the host)."""
        return self._master is None

    @property
    def error(self) -> BaseException | None:
        """An exception that stopped the server thread, if any (also logged)."""
        return self._error

    def vanish(self) -> None:
        """Close the master side now: the host's next read or write fails (EIO)."""
        if self._master_closed.is_set():
            return
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._vanish_requested.set()
            self._wake()
            if self._master_closed.wait(2.0):
                return
        self._close_master()

    def close(self) -> None:
        """Stop the server thread and close the pty pair (idempotent)."""
        self._stop.set()
        self._wake()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(2.0)
        self._close_master()
        for attr in ("_slave", "_wake_r", "_wake_w"):
            fd = getattr(self, attr)
            if fd is not None:
                setattr(self, attr, None)
                try:
                    os.close(fd)
                except OSError:
                    pass

    def __enter__(self) -> PtyServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._stop.is_set() else ("vanished" if self.vanished else "serving")
        return f"<PtyServer {self.port} {state}>"

    # ------------------------------------------------------------------ thread

    def _wake(self) -> None:
        fd = self._wake_w
        if fd is not None:
            try:
                os.write(fd, b"x")
            except OSError:
                pass

    def _close_master(self) -> None:
        fd, self._master = self._master, None
        if fd is not None:
            try:
                os.close(fd)
            except OSError:
                pass
            logger.info("pty %s: master closed (port vanished for the host)", self.port)
        self._master_closed.set()

    def _run(self) -> None:
        emulator = self.emulator
        try:
            while not self._stop.is_set():
                if self._vanish_requested.is_set() or emulator.vanished:
                    self._close_master()
                    return
                timeout = self._poll_interval_s
                due = emulator.next_event_time()
                if due is not None:
                    timeout = min(timeout, max(0.0, due - time.monotonic()))
                readable, _, _ = select.select([self._master, self._wake_r], [], [], timeout)
                if self._wake_r in readable:
                    os.read(self._wake_r, 64)
                    continue
                now = time.monotonic()
                if self._master in readable:
                    try:
                        data = os.read(self._master, 4096)
                    except OSError as exc:  # EIO: nobody has the slave open any more
                        logger.debug("pty %s: read: %s", self.port, exc)
                        time.sleep(self._poll_interval_s)
                        continue
                    out = emulator.feed(data, now)
                else:
                    out = emulator.poll(now)
                if emulator.vanished:
                    self._close_master()
                    return
                self._write_all(out)
        except Exception as exc:  # noqa: BLE001 - must not die silently
            self._error = exc
            logger.exception("CS-2000 emulator on %s stopped", self.port)

    def _write_all(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            written = os.write(self._master, view)
            view = view[written:]


def serve_on_pty(
    emulator: CS2000Emulator,
    time_scale: float | None = None,
    poll_interval_s: float = 0.005,
) -> PtyServer:
    """Serve ``emulator`` on a new pseudo-terminal; return the running server.

    Parameters
    ----------
    emulator
        The state machine to serve.
    time_scale
        If given, replaces ``emulator.time_scale`` (1 = real timing,
        0 = no waiting).
    poll_interval_s
        Longest wait between two polls of the emulator.

    Returns
    -------
    PtyServer
        With ``.port`` (open it with ``CS2000(server.port)``), ``.close()``
        and ``.vanish()``; also a context manager.

    Examples
    --------
    >>> import numpy as np
    >>> from instruments.cs2000 import CS2000, CS2000Emulator
    >>> emulator = CS2000Emulator(lambda: np.full(401, 1e-3), time_scale=0, seed=1)
    >>> with serve_on_pty(emulator) as server, CS2000(server.port) as cs:   # doctest: +SKIP
    ...     cs.identify().model
    'CS-2000'
    """
    if time_scale is not None:
        emulator.time_scale = time_scale
    return PtyServer(emulator, poll_interval_s=poll_interval_s)
