"""Bearing line sources take a bearing's own elements where it has them: the FVA model's
bearings by designation (ISO 15 / ISO 355 boundary dimensions typed here: 6210 50 x 90 mm,
33014 70 x 110 mm, 33012 60 x 95 mm) get pitch diameter (d + D) / 2 and their element
count, not the housing bore's coupling-point count."""
import pytest

from vibrogear.analyses.nvh.line_sources import bearing_geometry
from vibrogear.config import load_scene

FVA = "tests/data/rexs/FVA-Industriegetriebe_2stufig_1-4.rexs"


def test_designated_bearings_bring_their_own_elements():
    rows = {r["name"]: r for r in bearing_geometry(load_scene(FVA))}
    for name, d, D in (("bearing33", 50.0, 90.0), ("bearing34", 70.0, 110.0),
                       ("bearing35", 60.0, 95.0)):
        assert rows[name]["from"] == "the bearing's element set"
        assert rows[name]["pitch_m"] == pytest.approx(0.5 * (d + D) * 1e-3, rel=1e-12)
    assert rows["bearing33"]["elements"] == 10          # a 6210 deep-groove: 10 balls
    # the housing bore of the input/output axis has the 6210's 10 coupling points; the
    # tapered bearings on that axis keep their own (more) rollers
    assert rows["bearing34"]["elements"] > 10 and rows["bearing35"]["elements"] > 10
