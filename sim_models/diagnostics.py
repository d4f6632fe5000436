"""How a simulator got its numbers: the diagnostics every simulator's Solution carries, with
the same names and units in MuJoCo and pymunk (issue 12)."""

from __future__ import annotations

from dataclasses import dataclass, fields


@dataclass(frozen=True)
class RunDiagnostics:
    """The common diagnostics of one simulator run; a simulator adds its own beside them
    (:meth:`as_dict`)."""

    #: ``settle``, ``driven`` or ``constraint_solve``.
    method: str
    #: Simulator steps (or solver passes) the reading took.
    steps: int
    wall_time_s: float
    #: The largest joint speed left at the reading (m/s, or rad/s times the link scale).
    residual_velocity: float
    #: The largest gap at a joint the model closes by a constraint, m.
    loop_violation: float
    #: How far the reading's pose is from the analytic pose, m (rad for a bare angle).
    pose_drift: float
    #: The simulator's own warnings raised during the run, joined by `` | ``.
    warnings: str = ""

    def as_dict(self, **extra: float | str) -> dict[str, float | str]:
        """The diagnostics as a Solution carries them: these keys first, then ``extra``."""
        # Field by field: dataclasses.asdict deep-copies, a third of an exact solve's time.
        common: dict[str, float | str] = {k: getattr(self, k) for k in COMMON_KEYS}
        if self.warnings:
            common["warnings"] = self.warnings
        return common | extra


#: The keys every simulator solution's diagnostics have.
COMMON_KEYS = tuple(f.name for f in fields(RunDiagnostics) if f.name != "warnings")
