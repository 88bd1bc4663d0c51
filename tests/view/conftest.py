"""Fixtures of the ``marchlab view`` window's tests.

The window needs the gpu backend, imgui-bundle and a display: pytest-xvfb starts Xvfb for
the session where it is installed (`make test` installs it). A test taking the ``window``
fixture is skipped, saying why, where one is missing, or fails where ``make test`` sets
``MARCHLAB_REQUIRE_VIEW=1``: the view must run there.
"""

from __future__ import annotations

import os

import pytest

from required_backends import need_backend

REQUIRE = "MARCHLAB_REQUIRE_VIEW"


@pytest.fixture
def window():
    """Skip (or fail, where required) unless a view window can open here."""
    need_backend("gpu")
    from marchlab.view_window import window_problem
    problem = window_problem()
    if problem is None:
        return
    if os.environ.get(REQUIRE):
        pytest.fail(f"the view cannot open a window: {problem} (required by {REQUIRE}=1)",
                    pytrace=False)
    pytest.skip(problem)
