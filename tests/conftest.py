"""Shared test settings.

Hypothesis runs derandomised (the same examples every run) so that CI is reproducible; use
``--hypothesis-profile=explore`` locally to search with fresh random examples.
"""

from hypothesis import settings

settings.register_profile("marchlab", derandomize=True, deadline=None, max_examples=200)
settings.register_profile("explore", deadline=None, max_examples=2000)
settings.load_profile("marchlab")
