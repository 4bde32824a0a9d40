"""Shared test configuration: the Hypothesis profiles (fixtures shared by one folder live
in that folder's conftest.py).

Profiles: ``default`` (the suite's own per-test settings), ``ci`` (the same, derandomized,
so a CI run is repeatable) and ``thorough`` (1000 examples where a test sets no count of
its own, for a long local run): ``pytest --hypothesis-profile=thorough``.
"""

import os

from hypothesis import HealthCheck, settings

settings.register_profile("default", deadline=None)
settings.register_profile("ci", deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("thorough", deadline=None, max_examples=1000)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE",
                                     "ci" if os.environ.get("CI") else "default"))

