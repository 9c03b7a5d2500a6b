"""Measurement sequences: plans, the crash-safe journal, the runner and its exports (no Qt).

* :mod:`.plans`: which patches a calibration shows (``paper``, ``quick``, plan files);
* :mod:`.journal`: the append-only, fsynced JSON-lines journal and its reader;
* :mod:`.runner`: :class:`~.runner.MeasurementRun`, a generator worker that shows,
  measures and journals each patch, resumes a killed run, and exports the session;
* :mod:`.eta`: the remaining-time estimate that knows dark patches take longer;
* :mod:`.ti3`: the Argyll CGATS ``.ti3`` export;
* :mod:`.simulation`: the simulated headset measured by the CS-2000 emulator on a pty.
"""

__all__: list[str] = []
