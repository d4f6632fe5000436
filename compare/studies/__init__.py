"""Assumption studies (issue 6): each is a sweep run on the simulators, with a figure
and a one-line conclusion computed from the data.

``STUDIES`` maps a study's name to the module:function that runs it; each takes
``quick`` (fewer points, for tests) and returns a
:class:`~mechcheck.studies.common.StudyResult`.
"""

from __future__ import annotations

import importlib

from mechcheck.studies.common import Study, StudyResult

STUDIES: dict[str, str] = {
    "quasi_static": "mechcheck.studies.quasi_static:run",
    "quasi_static_motion": "mechcheck.studies.quasi_static_motion:run",
    "superposition_friction": "mechcheck.studies.superposition_friction:run",
    "friction_angle": "mechcheck.studies.friction_angle:run",
    "massless": "mechcheck.studies.massless:run",
    "rigid_joints": "mechcheck.studies.rigid_joints:run",
    "near_toggle": "mechcheck.studies.near_toggle:run",
}


def load(name: str) -> Study:
    if name not in STUDIES:
        raise KeyError(f"unknown study {name!r}; studies: {', '.join(STUDIES)}")
    module, function = STUDIES[name].split(":")
    study: Study = getattr(importlib.import_module(module), function)
    return study


def run_study(name: str, quick: bool = False) -> StudyResult:
    return load(name)(quick)
