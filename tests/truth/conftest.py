"""Fixtures of the ground-truth tests: ``embree`` skips a test, with the reason, where the
optional embree extra (embreex and scikit-image) is not installed."""

import importlib.util

import pytest


@pytest.fixture(scope="session")
def embree():
    """Skip unless embreex and scikit-image can be imported (``pip install 'marchlab[embree]'``)."""
    missing = [name for name in ("embreex", "skimage") if importlib.util.find_spec(name) is None]
    if missing:
        pytest.skip(f"the embree ground truth needs {' and '.join(missing)}: "
                    "pip install 'marchlab[embree]'")
