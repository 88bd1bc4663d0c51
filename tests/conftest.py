"""Shared test settings.

Hypothesis runs derandomised (the same examples every run) so that CI is reproducible; use
``--hypothesis-profile=explore`` locally to search with fresh random examples.

``MARCHLAB_REQUIRE_BACKENDS`` (tests/required_backends.py) names backends whose tests must
run rather than skip; a name it does not know stops the run before any test.
"""

from hypothesis import settings

from required_backends import required_backends

settings.register_profile("marchlab", derandomize=True, deadline=None, max_examples=200)
settings.register_profile("explore", deadline=None, max_examples=2000)
settings.load_profile("marchlab")


def pytest_configure(config):
    required_backends()          # raises pytest.UsageError for an unknown backend name
