"""Turning and holding experiments in both simulators: a driver turned by a bounded-torque
servo until it turns fully or jams at its lock, and a crank held against an output load.
They measure what :mod:`mechcheck.analytic.theory` predicts (driver ranges, dead
positions, Grashof classes, force amplification) from the simulators' own state:
the oracles of ``test_locks.py`` and ``test_theory_sim.py``."""
