"""Worker threads of the window: the measurement run, and any slow call (reading and diagnosing a file).

Each worker is a :class:`~PySide6.QtCore.QThread` whose ``run`` does the work
and reports through signals, which Qt delivers in the GUI thread (queued):
no widget is ever touched from a worker, and an exception in a worker reaches
the window through :attr:`failed` instead of vanishing.

Why our own ``QThread`` rather than superqt's ``thread_worker``: the runner is
already a generator with its own ``pause``/``resume``/``cancel``, which act on
the instrument *during* a measurement (``cancel`` sends ``MEAS,0``), while
``thread_worker``'s pause and quit act only between two ``yield``s, i.e.
after the patch in flight (tens of seconds on a dark patch). And
``thread_worker`` runs on a ``QThreadPool``, whose runnables cannot each be
``wait()``-ed at teardown; a ``QThread`` can, and the window waits for every
one before it closes.
"""

from __future__ import annotations

import logging
import threading
from typing import Callable

from PySide6.QtCore import QThread, Signal

from workbench.errors import WorkbenchError
from workbench.gui.calibration_setup import CalibrationSetup, open_run
from workbench.measurement.adaptive import plan_state as adaptive_plan_state

__all__ = ["CallWorker", "MeasurementWorker", "describe_error"]

_LOG = logging.getLogger(__name__)


def describe_error(error: BaseException) -> str:
    """The message a user reads: a :class:`WorkbenchError`'s own text, else the type and the text."""
    if isinstance(error, WorkbenchError):
        return str(error)
    return f"{type(error).__name__}: {error}"


class CallWorker(QThread):
    """Runs ``function()`` off the GUI thread; :attr:`done` carries its result, :attr:`failed` its error.

    Connect to the signals before :meth:`start`.
    """

    done = Signal(object)
    failed = Signal(str)

    def __init__(self, function: Callable[[], object], parent=None):
        super().__init__(parent)
        self._function = function

    def run(self) -> None:  # noqa: D401 - Qt's name
        try:
            result = self._function()
        except Exception as error:  # noqa: BLE001 - every error reaches the user
            _LOG.debug("worker failed", exc_info=True)
            self.failed.emit(describe_error(error))
            return
        self.done.emit(result)


class MeasurementWorker(QThread):
    """Runs a calibration (:func:`~workbench.gui.calibration_setup.open_run`) and emits each runner event.

    Attributes
    ----------
    event(object)
        Each event of :meth:`MeasurementRun.events` (``RunStarted`` …
        ``RunFinished``), in order.
    countdown(float, float)
        Remaining and total seconds of the measurement in flight.
    plan_state(object)
        With a dynamic plan (the adaptive one): its
        :class:`~workbench.measurement.adaptive.PlanState` once the run has
        started and after each patch (the plan so far, the latest decision,
        the predicted held-out ΔE00, the budget left).
    failed(str)
        The run could not start, or stopped (``RunAborted``); the message says
        what to do.

    :meth:`pause`, :meth:`resume` and :meth:`cancel` may be called at any
    time, also before the instrument is open (a cancel then takes effect as
    soon as the run exists; while the run waits for the headset's browser, a
    cancel stops the wait).
    """

    event = Signal(object)
    countdown = Signal(float, float)
    plan_state = Signal(object)
    failed = Signal(str)

    def __init__(self, setup: CalibrationSetup, window_display=None, parent=None, *, webxr_server=None):
        super().__init__(parent)
        self.setup = setup
        self._window_display = window_display
        self._webxr_server = webxr_server
        self._lock = threading.Lock()
        self._run = None
        self._cancelled = False
        self._cancel_wait = threading.Event()  # stops the wait for the headset's browser
        self._paused = False

    @property
    def cancelled(self) -> bool:
        """Whether :meth:`cancel` was called."""
        return self._cancelled

    def run(self) -> None:  # noqa: D401 - Qt's name
        try:
            with open_run(self.setup, self._window_display, on_countdown=self.countdown.emit,
                          webxr_server=self._webxr_server, cancel=self._cancel_wait) as run:
                with self._lock:
                    self._run = run
                    if self._paused:
                        run.pause()
                    if self._cancelled:
                        run.cancel()
                dynamic = run.planner is not None
                for event in run.events():
                    self.event.emit(event)
                    if dynamic:  # after each event: a decision is taken between two patches
                        self.plan_state.emit(adaptive_plan_state(run.journal_so_far()))
        except Exception as error:  # noqa: BLE001 - every error reaches the user
            _LOG.debug("measurement worker failed", exc_info=True)
            self.failed.emit(describe_error(error))
        finally:
            with self._lock:
                self._run = None

    def pause(self) -> None:
        with self._lock:
            self._paused = True
            if self._run is not None:
                self._run.pause()

    def resume(self) -> None:
        with self._lock:
            self._paused = False
            if self._run is not None:
                self._run.resume()

    def cancel(self) -> None:
        with self._lock:
            self._cancelled = True
            self._cancel_wait.set()
            if self._run is not None:
                self._run.cancel()
