"""The documentation states what the code does."""

import re
from pathlib import Path

from marchlab import docgen
from scene_model import shapes
from scene_model.scene import Light, RenderSettings

ROOT = Path(__file__).resolve().parent.parent


def test_scene_format_field_reference_is_generated_from_the_current_code():
    """docs/scene-format.md's field tables equal what `python -m marchlab.docgen` writes."""
    text = docgen.DOC.read_text()
    assert docgen.updated(text) == text, "run: python -m marchlab.docgen"


def test_field_reference_documents_every_node_light_and_render_setting():
    text = docgen.reference()
    for kind in shapes.node_kinds():
        assert f'`type = "{kind}"`' in text
    for cls in Light.__subclasses__():
        assert f'`type = "{cls.kind}"`' in text
    for name in RenderSettings.__dataclass_fields__:
        assert f"| `{name}` |" in text


def test_every_field_has_a_doc_string():
    """An undocumented field would show an empty 'meaning' cell in the reference."""
    empty = re.findall(r"^\| `(\w+)` \|[^\n]*\|  \|$", docgen.reference(), flags=re.M)
    assert empty == []


def test_readme_shows_the_two_setup_commands_and_its_picture_exists():
    readme = (ROOT / "README.md").read_text()
    assert "make demo" in readme and "make test" in readme
    for image in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", readme):
        assert (ROOT / image).is_file(), image
