"""MARCHLAB_REQUIRE_BACKENDS turns the skip of a missing backend into a failure that names it.

Each test runs a small pytest session (pytester, in this process) whose tests take the
backend fixtures of the equivalence suite and the hard cases as they are, on a "machine"
where every backend but numpy is made unavailable with a reason of the test's own. Unset,
those tests are skipped with the reason; required, they fail with the backend's name, the
reason and the variable; an unknown name stops the run and lists the known backends.
"""

from __future__ import annotations

import pytest

import required_backends
from marchlab.render import BACKENDS

pytest_plugins = ["pytester"]

REASON = "no such device (made up by the test)"

# (module holding the fixture, fixture, tests that need no backend, tests per missing backend)
FIXTURES = {"equivalence": ("equivalence.conftest", "backend", 0, {"gpu": 1, "opencl": 1}),
            "hard_cases": ("hard_cases.conftest", "renderer", 2, {"gpu": 1, "opencl": 2})}


@pytest.fixture
def only_numpy_runs(monkeypatch):
    """Every backend but numpy is unavailable, for `REASON`."""
    monkeypatch.setattr(required_backends, "why_unavailable",
                        lambda backend: None if backend == "numpy" else REASON)


def run_suite(pytester, which: str):
    """Run one test that takes the fixture of ``which``, once per backend it offers."""
    module, fixture, _, _ = FIXTURES[which]
    pytester.makeconftest(f"""
        from {module} import {fixture}
        from required_backends import required_backends

        def pytest_configure(config):
            required_backends()
        """)
    pytester.makepyfile(f"""
        def test_body({fixture}):
            pass
        """)
    return pytester.runpytest("-rs")


@pytest.mark.parametrize("which", FIXTURES)
def test_unset_variable_skips_a_missing_backend_with_its_reason(pytester, monkeypatch,
                                                                only_numpy_runs, which):
    monkeypatch.delenv(required_backends.VARIABLE, raising=False)
    result = run_suite(pytester, which)
    _, _, plain, missing = FIXTURES[which]
    result.assert_outcomes(passed=plain, skipped=sum(missing.values()))
    for backend in missing:
        result.stdout.fnmatch_lines([f"SKIPPED*{backend} backend unavailable: {REASON}*"])


@pytest.mark.parametrize("which", FIXTURES)
def test_required_backends_fail_naming_the_backend_and_the_reason(pytester, monkeypatch,
                                                                  only_numpy_runs, which):
    monkeypatch.setenv(required_backends.VARIABLE, "gpu,opencl")
    result = run_suite(pytester, which)
    _, _, plain, missing = FIXTURES[which]
    result.assert_outcomes(passed=plain, errors=sum(missing.values()))
    assert result.ret == pytest.ExitCode.TESTS_FAILED
    for backend in missing:
        result.stdout.fnmatch_lines([f"*{backend} backend unavailable: {REASON} "
                                     f"(required by MARCHLAB_REQUIRE_BACKENDS=gpu,opencl)*"])


def test_a_backend_not_named_is_still_skipped(pytester, monkeypatch, only_numpy_runs):
    monkeypatch.setenv(required_backends.VARIABLE, " opencl ")
    result = run_suite(pytester, "equivalence")
    result.assert_outcomes(skipped=1, errors=1)
    result.stdout.fnmatch_lines([f"SKIPPED*gpu backend unavailable: {REASON}*"])
    result.stdout.fnmatch_lines(["*opencl backend unavailable*required by*"])


def test_unknown_backend_name_stops_the_run_listing_the_known_ones(pytester, monkeypatch,
                                                                    only_numpy_runs):
    monkeypatch.setenv(required_backends.VARIABLE, "gpu,vulkan")
    result = run_suite(pytester, "equivalence")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    known = ", ".join(BACKENDS)
    result.stderr.fnmatch_lines([f"*MARCHLAB_REQUIRE_BACKENDS='gpu,vulkan': unknown backend "
                                 f"vulkan; the known backends are {known}*"])

