"""A bearing between two shafts (the FVA input shaft running in its output shaft): its
element compressions vanish under any common rigid translation of the two journals and
equal e_k . (u_inner - u_outer) for a relative one, so the shafts load each other, not the
ground."""
from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import scene_from_dict
from vibrogear.config.rexs import import_rexs
from vibrogear.models.gearbox.model import build_gearbox

XML = Path(__file__).resolve().parents[1] / "data" / "rexs" / "FVA-Industriegetriebe_2stufig_1-4.rexs"


@pytest.fixture(scope="module")
def fva_rolling():
    """The FVA scene with the concept bearing 36 as a cylindrical roller bearing NU 210
    (50 x 90 x 20 mm) between shafts 12 and 14."""
    data = import_rexs(XML).data
    b = next(x for x in data["gearbox"]["bearings"] if x["name"] == "bearing36")
    b.pop("type"), b.pop("stiffness")
    b["designation"] = "NU 210"
    return scene_from_dict(data)


def _value(vec, q):
    return sum(float(v @ q[s][i]) for s, i, v in vec.parts)


def test_relative_motion_only(fva_rolling):
    sc = fva_rolling
    gm = build_gearbox(sc, master_counts=[6, 6, 6])
    rolling = [c for c in gm.contacts if c.name.startswith("bearing36:")]
    assert len(rolling) >= 3
    sizes = {}
    for c in rolling:
        for s, i, _ in c.vector.parts:
            sizes[s] = max(sizes.get(s, 0), 6 * (int(i.max()) // 6 + 1))
    rng = np.random.default_rng(1)
    t = rng.normal(size=3)
    common = {s: np.zeros(sizes[s]) for s in sizes}
    for s in common:
        common[s].reshape(-1, 6)[:, :3] = t            # every node of both shafts translated
    for c in rolling:
        assert abs(_value(c.vector, common)) < 1e-12
    # the inner shaft (12, index 0) moved by dx along rotor X, the outer (14) at rest
    rel = {s: np.zeros(sizes[s]) for s in sizes}
    rel[0].reshape(-1, 6)[:, 0] = 1e-6
    angles = 2 * np.pi * np.arange(len(rolling)) / len(rolling)
    got = np.array([_value(c.vector, rel) for c in rolling])
    assert got == pytest.approx(1e-6 * np.cos(angles), abs=1e-18)
    assert {s for c in rolling for s, _, _ in c.vector.parts} == {0, 2}
