"""The rig tests' collection hook."""

import pytest


def pytest_collection_modifyitems(config, items):
    """Slow rig tests (the whole demo through the rig) run only with PIHYST_SLOW=1 or
    when chosen with -m slow, so the default suite stays quick."""
    import os
    if os.environ.get("PIHYST_SLOW") == "1" or "slow" in (config.getoption("-m") or ""):
        return
    skip = pytest.mark.skip(reason="slow: set PIHYST_SLOW=1 or run with -m slow")
    for item in items:
        if "slow" in item.keywords and "tests/rig" in str(item.path).replace("\\", "/"):
            item.add_marker(skip)
