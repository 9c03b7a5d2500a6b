"""Measurement sequences: plans, the crash-safe journal, the runner and its exports (no Qt).

* :mod:`.plans`: which patches a calibration shows (``paper``, ``quick``, plan files);
* :mod:`.journal`: the append-only, fsynced JSON-lines journal and its reader;
* :mod:`.runner`: :class:`~.runner.MeasurementRun`, a generator worker that shows,
  measures and journals each patch, resumes a killed run, and exports the session;
* :mod:`.eta`: the remaining-time estimate that knows dark patches take longer;
* :mod:`.ti3`: the Argyll CGATS ``.ti3`` export;
* :mod:`.simulation`: the simulated headset measured by the CS-2000 emulator on a pty;
* :mod:`.adaptive`: ``--plan adaptive``, the planner that chooses each next patch by the
  predicted held-out ΔE00 it removes per second of instrument time, with its reasons;
* :mod:`.planning_model`: the planner's Gaussian-process surrogate of what is still unknown;
* :mod:`.patch_cost`: a patch's instrument time, learned from this session's countdowns and times.
"""

__all__: list[str] = []
