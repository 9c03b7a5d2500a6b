"""Benchmark: ``diagnose`` on a 214-measurement session, wall time including interpreter start-up.

Goal (issue): under 2 s. The session is the ``paper`` plan measured on the
simulated headset with two hidden effects, written as a session CSV; the
command is run as a user runs it, ``python -m workbench diagnose FILE --json``,
in a fresh interpreter each time.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

__all__ = ["benchmark_diagnose"]


def benchmark_diagnose(repeats: int = 5) -> dict:
    """Wall-clock seconds of ``diagnose`` runs (each in a new interpreter)."""
    from workbench.diagnostics import diagnose
    from workbench.session import write_session_csv
    from workbench.simulated_sessions import simulate_session

    session = simulate_session({"black-offset": 0.006, "temporal-drift": 0.05}, seed=1)
    with tempfile.TemporaryDirectory() as folder:
        path = write_session_csv(session, Path(folder) / "session.csv")
        started = time.perf_counter()
        diagnose(session)
        in_process = time.perf_counter() - started
        walls = []
        for _ in range(repeats):
            started = time.perf_counter()
            subprocess.run([sys.executable, "-m", "workbench", "diagnose", str(path), "--json"],
                           check=True, capture_output=True)
            walls.append(time.perf_counter() - started)
        started = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import colour"], check=True, capture_output=True)
        import_colour = time.perf_counter() - started
    return {
        "measurements": len(session),
        "repeats": repeats,
        "wall_s_median": statistics.median(walls),
        "wall_s_min": min(walls),
        "wall_s_max": max(walls),
        "in_process_s": in_process,
        "python_plus_import_colour_s": import_colour,
        "goal_s": 2.0,
    }
