"""A peer's profile scored on the validation colours: ArgyllCMS's, the seed authors' method.

Every peer is fitted on exactly the session's fit rows and scored on the same
held-out rows with the convention of :func:`workbench.diagnostics.diagnose`
(CIEDE2000, CIELAB white the measured display white).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PeerScore", "peer_score"]


@dataclass(frozen=True)
class PeerScore:
    """A peer's model scored on the validation colours.

    ``unavailable`` is the reason when there is no score (the peer's tool is
    missing, the session lacks what its method needs, nothing held out); the
    figures are then None.
    """

    model: str
    n: int = 0
    mean_dE00: float | None = None
    p95_dE00: float | None = None
    max_dE00: float | None = None
    unavailable: str = ""

    def to_json(self) -> dict:
        return {"model": self.model, "n": self.n, "mean_dE00": self.mean_dE00,
                "p95_dE00": self.p95_dE00, "max_dE00": self.max_dE00,
                "unavailable": self.unavailable or None}


def peer_score(model: str, dE) -> PeerScore:
    """The score of ``model`` from its per-colour CIEDE2000 ``dE``."""
    dE = np.atleast_1d(np.asarray(dE, dtype=float))
    return PeerScore(model, n=int(dE.size), mean_dE00=float(dE.mean()),
                     p95_dE00=float(np.percentile(dE, 95)), max_dE00=float(dE.max()))
