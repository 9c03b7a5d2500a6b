"""Short background jobs on superqt's ``thread_worker``, each with a handle the page can wait on.

A page's slow, Qt-free call (a generator yielding rows, or a function) runs
in a superqt worker; its results, errors and end arrive as signals in the GUI
thread. superqt runs workers on a ``QThreadPool``, whose runnables cannot be
``wait()``-ed one by one, so :class:`Job` adds a :class:`threading.Event` set
when the work has left the worker, and pages wait on it at teardown.
(Measurement runs, which must act *during* an instrument wait, use
:mod:`workbench.gui.workers`' ``QThread``\\ s instead.)
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

from superqt.utils import thread_worker

__all__ = ["Job", "start_job"]


@dataclass
class Job:
    """A started worker and the event set when it has finished (normally, by error or by quit)."""

    worker: object
    done: threading.Event = field(default_factory=threading.Event)
    tag: str = ""

    @property
    def running(self) -> bool:
        return not self.done.is_set()

    def quit(self) -> None:
        """Ask a generator job to stop at its next ``yield`` (a function job runs to its end)."""
        quit_ = getattr(self.worker, "quit", None)
        if callable(quit_):
            quit_()

    def wait(self, timeout_s: float | None = None) -> bool:
        """Block until the job has finished; False on timeout."""
        return self.done.wait(timeout_s)


def start_job(function, *, generator: bool = False, returned=None, yielded=None, errored=None,
              finished=None) -> Job:
    """Run ``function()`` (a generator function when ``generator``) in a superqt worker.

    The callbacks are connected to the worker's ``returned``, ``yielded``,
    ``errored`` and ``finished`` signals before it starts, so none is missed.
    """
    done = threading.Event()
    if generator:
        @thread_worker(start_thread=False)
        def work():
            try:
                yield from function()
            finally:
                done.set()
    else:
        @thread_worker(start_thread=False)
        def work():
            try:
                return function()
            finally:
                done.set()
    worker = work()
    # superqt drops a quit generator without closing it, so the ``finally``
    # above would run only at garbage collection: the worker's own end
    # (emitted in its thread, whatever the way out) sets the event too.
    from PySide6.QtCore import Qt

    worker.finished.connect(done.set, Qt.ConnectionType.DirectConnection)
    for signal, slot in ((worker.returned, returned), (worker.errored, errored),
                         (worker.finished, finished)):
        if slot is not None:
            signal.connect(slot)
    if yielded is not None:
        worker.yielded.connect(yielded)
    worker.start()
    return Job(worker=worker, done=done)
