"""The simulators: one package per simulator (``mujoco``, ``pymunk``).

Each package declares its backends as ``BACKENDS`` in its ``__init__``
(:class:`~mechcheck.analytic.contract.Backend`), without importing its simulator, and
:mod:`mechcheck.backends` finds every package here: adding a simulator is adding a package,
with no edit anywhere else (``tests/test_backend_contract.py`` adds a fake one).
"""
