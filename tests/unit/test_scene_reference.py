"""docs/scene-reference.md is generated from the config specs and kept equal to them."""
import dataclasses
import re
from pathlib import Path

from vibrogear.config.model.gearbox import GearboxConfig
from vibrogear.config.model.gearbox_supports import ExternalCouplingConfig, GearboxBearingConfig
from vibrogear.config.reference import scene_reference_markdown

DOC = Path(__file__).resolve().parents[2] / "docs" / "scene-reference.md"


def test_scene_reference_equals_the_code():
    assert DOC.read_text() == scene_reference_markdown(), (
        "docs/scene-reference.md is stale: python -m vibrogear.config.reference > "
        "docs/scene-reference.md")


def test_every_gearbox_key_is_listed():
    text = DOC.read_text()
    for cls, section in ((GearboxConfig, "gearbox"), (GearboxBearingConfig, "gearbox.bearings"),
                         (ExternalCouplingConfig, "gearbox.couplings")):
        body = text.split(f"## [{section}]\n", 1)[1].split("\n## ", 1)[0]
        keys = re.findall(r"^\| `(\w+)` \|", body, re.M)
        assert keys == [f.name for f in dataclasses.fields(cls)]
