"""The documentation site builds with warnings as errors and has the pages a course needs.

One Sphinx build (about 30 s on two cores) into a temporary folder, with the lessons'
execution switched off: the notebooks are executed by their own tests, `make docs` runs them
for the site. Every other test reads the HTML of that build.
"""

from __future__ import annotations

import html
import importlib
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

from marchlab.cli import build_parser
from scene_model import shapes
from scene_model.scene import RenderSettings

pytest.importorskip("sphinx", reason="the docs extra is not installed: pip install -e '.[docs]'")
pytest.importorskip("myst_nb", reason="the docs extra is not installed: pip install -e '.[docs]'")

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("scene_model", "marchlab", "reference_cpu", "physics", "gpu_shader")
MATHS = ("sphere-tracing", "phong", "shadows", "reflections", "impulses", "equivalence")


@pytest.fixture(scope="module")
def build(tmp_path_factory) -> subprocess.CompletedProcess:
    """The site built as `make docs` builds it (-W --keep-going), without running lessons.

    --keep-going writes every page even when a warning fails the build, so the tests of the
    pages below still say what they find; the first test is the one about warnings.
    """
    out = tmp_path_factory.mktemp("site")
    result = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html",
         "-D", "nb_execution_mode=off", "-d", str(out / "doctrees"),
         str(ROOT / "docs"), str(out / "html")],
        capture_output=True, text=True, timeout=600)
    result.html = out / "html"
    return result


@pytest.fixture(scope="module")
def site(build) -> Path:
    if not (build.html / "index.html").is_file():
        pytest.fail(f"the site was not built:\n{build.stderr[-6000:]}")
    return build.html


def text_of(page: Path) -> str:
    """The visible text of an HTML page, tags removed."""
    return html.unescape(re.sub(r"<[^>]+>", "", page.read_text()))


def subcommands() -> dict[str, object]:
    parser = build_parser()
    (action,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    return dict(action.choices)


def test_site_builds_with_warnings_as_errors_and_none_is_raised(build):
    assert build.returncode == 0, (f"sphinx-build -W failed (exit {build.returncode}):\n"
                                   + build.stderr[-6000:])


def test_site_has_its_front_pages_and_the_two_commands(site):
    for page in ("index", "getting-started", "lessons", "cli", "scene-format", "api/index",
                 "sources", *MATHS):
        assert (site / f"{page}.html").is_file(), page
    start = text_of(site / "getting-started.html")
    assert "make demo" in start and "make test" in start and "make docs" in start


def test_cli_reference_has_a_section_per_subcommand_with_every_option(site):
    page = (site / "cli.html").read_text()
    text = text_of(site / "cli.html")
    for name, sub in subcommands().items():
        assert f'id="cli-{name}"' in page, f"no section for marchlab {name}"
        for action in sub._actions:
            for option in action.option_strings:
                if option not in ("-h", "--help"):
                    assert option in text, f"marchlab {name} {option} is not documented"


def test_api_reference_documents_every_module_and_reference_cpu_march(site):
    for package in PACKAGES:
        page = (site / "api" / f"{package}.html").read_text()
        root = importlib.import_module(package)
        names = [package] + [m.name for m in pkgutil.walk_packages(root.__path__, f"{package}.")]
        for name in names:
            assert f'id="module-{name}"' in page, f"{name} is missing from api/{package}.html"
    march = (site / "api" / "reference_cpu.html").read_text()
    assert 'id="reference_cpu.march.march"' in march


def test_maths_pages_link_to_the_functions_they_describe(site):
    links = {"sphere-tracing": "reference_cpu.march.march",
             "phong": "reference_cpu.shading.shade_phong",
             "shadows": "reference_cpu.shadows.soft_shadow",
             "reflections": "reference_cpu.render.Tracer.lit_color",
             "impulses": "physics.impulses.collision_impulse",
             "equivalence": "marchlab.compare.failures"}
    for page, target in links.items():
        package = target.split(".")[0]
        assert f'href="api/{package}.html#{target}"' in (site / f"{page}.html").read_text(), page


def test_scene_field_reference_on_the_site_covers_every_node_and_render_setting(site):
    text = text_of(site / "scene-format.html")
    for kind in shapes.node_kinds():
        assert f'type = "{kind}"' in text, kind
    for name in RenderSettings.__dataclass_fields__:
        assert name in text, name


def test_every_lesson_notebook_is_rendered_and_listed(site):
    lessons = sorted((ROOT / "lessons").glob("*.ipynb"))
    index = (site / "lessons.html").read_text()
    for notebook in lessons:
        assert (site / "lessons" / f"{notebook.stem}.html").is_file(), notebook.name
        assert f'href="lessons/{notebook.stem}.html"' in index, notebook.name


CDN = re.compile(r"""(?:src|href)\s*=\s*["']?(?:https?:)?//[^"'\s>]*"""
                 r"""(?:cdn|unpkg|jsdelivr|mathjax|require(?:js)?\b)[^"'\s>]*""", re.I)


def test_no_page_loads_a_script_or_style_from_a_cdn(site):
    offenders = {}
    for page in site.rglob("*.html"):
        found = CDN.findall(page.read_text(encoding="utf-8", errors="replace"))
        if found:
            offenders[str(page.relative_to(site))] = found[:3]
    assert offenders == {}


def test_mathjax_is_served_from_the_site_itself(site):
    page = (site / "sphere-tracing.html").read_text(encoding="utf-8")
    scripts = re.findall(r"<script[^>]*src=\"([^\"]*mathjax[^\"]*)\"", page, re.I)
    assert scripts, "the formulas' page loads no MathJax"
    for source in scripts:
        assert not re.match(r"(https?:)?//", source), source
        assert (site / source.split("?")[0]).resolve().is_file(), source


def test_formulas_render_offline_in_a_browser_with_the_network_blocked(site):
    # Debian's Chromium, driven by Playwright, opens a maths page from disk with every
    # request off this machine refused: MathJax (served by the site) must typeset its
    # formulas, with no MathJax error and no raw TeX left on the page.
    import shutil
    playwright = pytest.importorskip("playwright.sync_api", reason="the dev extra")
    chromium = next((shutil.which(n) for n in ("chromium", "chromium-browser")
                     if shutil.which(n)), None)
    if chromium is None:
        import os
        if os.environ.get("MARCHLAB_REQUIRE_BROWSER"):
            pytest.fail("no chromium here (required by MARCHLAB_REQUIRE_BROWSER=1)",
                        pytrace=False)
        pytest.skip("no chromium here (apt-get install chromium)")
    blocked = []
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=["--no-sandbox"])
        try:
            page = browser.new_page()

            def only_local(route):
                if route.request.url.startswith("file:"):
                    return route.continue_()
                blocked.append(route.request.url)
                return route.abort()

            page.route("**/*", only_local)
            page.goto((site / "sphere-tracing.html").as_uri())
            page.wait_for_selector("mjx-container", timeout=60_000)
            page.wait_for_timeout(1000)
            typeset = page.locator("mjx-container").count()
            errors = page.locator("mjx-merror").count()
            text = page.inner_text("article") if page.locator("article").count() else ""
        finally:
            browser.close()
    assert typeset >= 10
    assert errors == 0
    assert "\\frac" not in text and "\\varepsilon" not in text
    assert blocked == []                        # it asked for nothing off this machine
