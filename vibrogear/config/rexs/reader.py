"""Reading a REXS file (XML ``.rexs`` or JSON ``.rexsj``) into one neutral model.

REXS (rexs.info) describes a gear unit as *components* (each with an id, a type and
attributes carrying a value and a unit), *relations* (typed, with references to components
by id and role) and a *load spectrum* (load cases whose components carry the operating
attributes: speeds, torques, forces).  Both encodings hold the same model:

* XML: ``<model version=...>`` with ``<relations>``, ``<components>`` and
  ``<load_spectrum>``; ``<attribute id= unit=>`` holds a value or an ``<array>`` of ``<c>``;
* JSON: ``{"model": {"version", "relations": [{"id", "type", "refs": [{"id", "role",
  "hint"}]}], "components": [{"id", "type", "name", "attributes": [{"id", "unit",
  <kind>: value}]}], "load_spectrum": {"load_cases": [...]}}}``.

Every value is converted to SI units here (lengths to m, moduli to Pa, densities to
kg/m^3, angles stay in degrees, speeds in rpm, torques in N m), from the unit the file
states.  A unit the table does not know, a missing attribute, a reference to a missing
component or a file that is neither raises :class:`~vibrogear.config.base.ConfigError`
naming the file, the component id and the attribute.
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..base import ConfigError

__all__ = ["RexsModel", "Component", "Relation", "read_rexs", "SUPPORTED_VERSIONS",
           "UNITS", "UNIT_FACTORS", "ATTRIBUTE_QUANTITY", "unit_key", "unit_factor"]

#: REXS versions read (attribute names as in 1.4; the versions differ in components this
#: importer does not map, e.g. 1.5's bevel and worm stages, which it refuses by name)
SUPPORTED_VERSIONS = ("1.0", "1.1", "1.2", "1.3", "1.4", "1.5", "1.6", "2.0")

#: unit (normalised by :func:`unit_key`) -> (quantity, factor to the SI unit this importer
#: uses).  The spellings of REXS 1.0-1.7 and 2.0 (their schemas' unit lists: ``°`` in 1.0-1.7
#: beside ``deg``, ``mum`` for micrometres, ``1 / min``, ``N m``, ``kg / dm^3``, ``N / mm^2``)
#: and the ones exporters write instead (``µm``, ``rpm``, ``Nm``, ``N*m``, ``MPa``, ...).
#: Angles stay in degrees, speeds in rpm; power in W, everything else SI.
UNITS = {
    "m": ("length", 1.0), "mm": ("length", 1e-3), "cm": ("length", 1e-2),
    "um": ("length", 1e-6),
    "deg": ("angle", 1.0), "°": ("angle", 1.0), "rad": ("angle", 180.0 / math.pi),
    "pa": ("stress", 1.0), "n/m^2": ("stress", 1.0), "n/mm^2": ("stress", 1e6),
    "mpa": ("stress", 1e6), "gpa": ("stress", 1e9), "kn/mm^2": ("stress", 1e9),
    "kg/m^3": ("density", 1.0), "kg/dm^3": ("density", 1e3), "g/cm^3": ("density", 1e3),
    "kg/mm^3": ("density", 1e9),
    "nm": ("torque", 1.0), "nmm": ("torque", 1e-3), "knm": ("torque", 1e3),
    "n": ("force", 1.0), "kn": ("force", 1e3),
    "1/min": ("speed", 1.0), "rpm": ("speed", 1.0), "min^-1": ("speed", 1.0),
    "u/min": ("speed", 1.0), "rad/s": ("speed", 30.0 / math.pi), "1/s": ("speed", 60.0),
    "w": ("power", 1.0), "kw": ("power", 1e3), "mw": ("power", 1e6),
    "n/m": ("stiffness", 1.0), "n/mm": ("stiffness", 1e3), "n/um": ("stiffness", 1e6),
    "kn/mm": ("stiffness", 1e6), "kn/um": ("stiffness", 1e9),
    "nmm/rad": ("rotational stiffness", 1e-3), "nm/rad": ("rotational stiffness", 1.0),
    "kg": ("mass", 1.0), "g": ("mass", 1e-3),
    "kgm^2": ("inertia", 1.0), "kgmm^2": ("inertia", 1e-6), "gmm^2": ("inertia", 1e-9),
    "%": ("fraction", 1.0), "c": ("temperature", 1.0), "°c": ("temperature", 1.0),
    "none": ("number", 1.0), "": ("number", 1.0), "-": ("number", 1.0),
}

#: the quantity of each attribute the importer reads as a number: a unit of another quantity
#: is an error naming both (a face width in degrees is a broken file, not a number to scale)
ATTRIBUTE_QUANTITY = {
    **{a: "length" for a in (
        "u_coordinate_on_shaft", "u_coordinate_on_shaft_inner_side",
        "u_coordinate_on_shaft_outer_side", "length", "outer_diameter_begin",
        "outer_diameter_end", "inner_diameter_begin", "inner_diameter_end", "face_width",
        "normal_module", "center_distance", "inner_diameter", "outer_diameter", "width",
        "reference_diameter", "reference_diameter_rolling_bearing", "diameter_of_rolling_element",
        "length_of_rolling_element", "operating_radial_bearing_clearance",
        "mounted_radial_bearing_clearance", "radial_bearing_clearance")},
    **{a: "angle" for a in ("helix_angle_reference_diameter", "helix_angle",
                            "normal_pressure_angle", "pressure_angle")},
    "elastic_modulus": "stress", "density": "density", "torque_around_u_axis": "torque",
    "rotational_speed": "speed", "power": "power", "axial_stiffness": "stiffness",
    "radial_stiffness": "stiffness", "mass_of_component": "mass",
    **{a: "inertia" for a in ("moment_of_inertia_u_axis", "moment_of_inertia_v_axis",
                              "moment_of_inertia_w_axis")},
    "load_duration_fraction": "fraction", "operating_time_fraction": "fraction",
    **{a: "number" for a in ("number_of_teeth", "poisson_ratio",
                             "addendum_modification_coefficient", "profile_shift_coefficient",
                             "number_of_rolling_elements")},
}

_MICRO = ("\u00b5", "\u03bc", "mu")     # micro sign, Greek mu, REXS's "mu" (mum, mus)


def unit_key(unit) -> str:
    """A unit as the table keys it: spaces, ``*``, ``·`` and ``⋅`` between factors dropped,
    ``²``/``³`` as ``^2``/``^3``, the micro prefix (``µ``, ``μ``, REXS's ``mu``) as ``u``,
    lower case (``N m``, ``Nm``, ``N*m`` and ``N·m`` are one unit)."""
    s = str(unit or "").strip()
    for a, b in (("\u00b2", "^2"), ("\u00b3", "^3"), ("\u00b7", ""), ("\u22c5", ""),
                 ("*", ""), ("\u2009", ""), ("\u00a0", "")):
        s = s.replace(a, b)
    s = re.sub(r"\s+", "", s)
    for m in _MICRO:
        s = re.sub(m + r"(?=m|s|$)", "u", s)
    return s.lower()


def unit_factor(unit, quantity: str | None = None) -> float | None:
    """The factor to SI of ``unit``; None where the table does not know it or it is not a
    unit of ``quantity``."""
    entry = UNITS.get(unit_key(unit))
    if entry is None or (quantity is not None and entry[0] != quantity
                         and {quantity, entry[0]} != {"number", "fraction"}):
        return None
    return entry[1]


#: kept for callers that scale by a raw unit string: every spelling of the table
UNIT_FACTORS = {k: v[1] for k, v in UNITS.items()}


def _empty(value) -> bool:
    return value is None or (isinstance(value, str) and not value.strip()) or \
        (isinstance(value, (list, tuple)) and not value)


@dataclass(frozen=True)
class Component:
    id: str
    type: str
    name: str
    attributes: dict            # attribute id -> (raw value, unit)

    def label(self) -> str:
        return f"{self.type} {self.id}" + (f" ({self.name})" if self.name else "")

    def has(self, attr: str) -> bool:
        return attr in self.attributes

    def raw(self, attr: str, source: str):
        if attr not in self.attributes:
            raise ConfigError(source, f"component {self.id} ({self.type}"
                              f"{', ' + repr(self.name) if self.name else ''}): missing "
                              f"attribute {attr!r}; fix: give it in the REXS file"
                              + (f" (a {ATTRIBUTE_QUANTITY[attr]})" if attr in
                                 ATTRIBUTE_QUANTITY else ""))
        return self.attributes[attr][0]

    def given(self, attr: str) -> bool:
        """The attribute is present with a value (an exporter's empty value is not given)."""
        return attr in self.attributes and not _empty(self.attributes[attr][0])

    def unit_error(self, attr: str, source: str, unit: str, quantity: str | None):
        known = sorted({u for u, (q, _) in UNITS.items() if u and (quantity is None
                                                                   or q == quantity)})
        what = f"a unit of {quantity} " if quantity else ""
        return ConfigError(source, f"component {self.id} ({self.type}): attribute {attr!r} "
                           f"has unit {unit!r}, which the importer does not know as {what}"
                           f"(known: {', '.join(known)}); fix: write the value in one of "
                           "these units")

    def number(self, attr: str, source: str, default: float | None = None) -> float:
        """The attribute in SI units (lengths m, angles deg, moduli Pa, ...), converted
        through :data:`UNITS`; an empty value counts as not given."""
        if not self.given(attr) and default is not None:
            return default
        value, unit = self.raw(attr, source), self.attributes[attr][1]
        if _empty(value):
            raise ConfigError(source, f"component {self.id} ({self.type}): attribute {attr!r} "
                              "is empty; fix: give its value")
        quantity = ATTRIBUTE_QUANTITY.get(attr)
        factor = unit_factor(unit, quantity)
        if factor is None:
            raise self.unit_error(attr, source, unit, quantity)
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise ConfigError(source, f"component {self.id} ({self.type}): attribute {attr!r} "
                              f"must be a number, got {value!r}") from None
        if not math.isfinite(x):
            raise ConfigError(source, f"component {self.id} ({self.type}): attribute {attr!r} "
                              f"must be finite, got {value!r}")
        return float(f"{x * factor:.12g}")    # 0.0045, not 0.0045000000000000005

    def vector(self, attr: str, source: str) -> tuple[float, float, float]:
        value, unit = self.raw(attr, source), self.attributes[attr][1]
        factor = unit_factor(unit) or 1.0
        try:
            v = tuple(float(c) * factor for c in value)
        except (TypeError, ValueError):
            v = ()
        if len(v) != 3 or not all(math.isfinite(c) for c in v):
            raise ConfigError(source, f"component {self.id} ({self.type}): attribute {attr!r} "
                              f"must be an array of 3 numbers, got {value!r}")
        return v

    def text(self, attr: str, source: str, default: str | None = None) -> str:
        if not self.given(attr) and default is not None:
            return default
        return str(self.raw(attr, source))

    def flag(self, attr: str, default: bool = False) -> bool:
        if attr not in self.attributes:
            return default
        v = self.attributes[attr][0]
        return v if isinstance(v, bool) else str(v).strip().lower() == "true"


@dataclass(frozen=True)
class Relation:
    id: str
    type: str
    refs: tuple                 # (role, component id, hint)

    def ref(self, role: str) -> str | None:
        return next((i for r, i, _ in self.refs if r == role), None)


@dataclass(frozen=True)
class RexsModel:
    source: str
    version: str
    application: str
    components: dict            # id -> Component
    relations: tuple
    load_cases: tuple           # ({component id: {attribute: (value, unit)}}, ...)
    unreferenced: tuple = field(default=())

    def component(self, cid: str, where: str) -> Component:
        if cid not in self.components:
            raise ConfigError(self.source, f"{where} refers to component {cid}, which the "
                              "file does not define")
        return self.components[cid]

    def of_type(self, *types: str) -> list[Component]:
        return [c for c in self.components.values() if c.type in types]

    def relations_of(self, rtype: str) -> list[Relation]:
        return [r for r in self.relations if r.type == rtype]

    def owner(self, part_id: str, owner_type: str) -> Component | None:
        """The component of ``owner_type`` that has ``part_id`` as an assembly part."""
        for r in self.relations_of("assembly"):
            if r.ref("part") == part_id and r.ref("assembly") is not None and \
                    self.components[r.ref("assembly")].type == owner_type:
                return self.components[r.ref("assembly")]
        return None


def _decode(code: str, text: str) -> list:
    """A coded array (REXS: base64 of little-endian float32 / float64 / int32)."""
    import base64
    import struct
    fmt = {"float32": "f", "float64": "d", "int32": "i"}.get(code)
    if fmt is None:
        return []
    raw = base64.b64decode((text or "").strip() + "==", validate=False)
    n = len(raw) // struct.calcsize(fmt)
    return list(struct.unpack(f"<{n}{fmt}", raw[:n * struct.calcsize(fmt)]))


def _xml_value(attr):
    arr = attr.find("array")
    if arr is not None:
        if arr.get("code"):
            return _decode(arr.get("code"), arr.text)
        return [c.text for c in arr.findall("c")]
    mat = attr.find("matrix")
    if mat is not None:
        return [[c.text for c in row.findall("c")] for row in mat.findall("r")]
    return (attr.text or "").strip()


def _xml_components(parent) -> dict:
    out = {}
    for c in parent.findall("component"):
        attrs = {a.get("id"): (_xml_value(a), a.get("unit", "") or "") for a in c.findall("attribute")}
        out[str(c.get("id"))] = (c.get("type", ""), c.get("name", "") or "", attrs)
    return out


def _read_xml(text: str, source: str):
    import xml.etree.ElementTree as ET
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ConfigError(source, f"not a REXS file: not well-formed XML ({exc})") from None
    if root.tag != "model":
        raise ConfigError(source, f"not a REXS file: the XML root is <{root.tag}>, expected "
                          "<model>")
    comps = _xml_components(root.find("components") if root.find("components") is not None
                            else root)
    rels = []
    for r in (root.find("relations") if root.find("relations") is not None else []):
        rels.append((str(r.get("id")), r.get("type", ""),
                     tuple((x.get("role", ""), str(x.get("id")), x.get("hint", "") or "")
                           for x in r.findall("ref"))))
    cases = []
    spectrum = root.find("load_spectrum")
    for lc in (spectrum.findall("load_case") if spectrum is not None else []):
        cases.append({cid: attrs for cid, (_, _, attrs) in _xml_components(lc).items()})
    return root.get("version", ""), root.get("applicationId", ""), comps, rels, cases


_JSON_KINDS = ("floating_point", "integer", "boolean", "string", "enum", "reference_component",
               "floating_point_array", "integer_array", "boolean_array", "string_array",
               "floating_point_matrix", "integer_matrix", "file_reference", "date_time",
               "array_of_integer_arrays", "enum_array", "floating_point_array_coded",
               "floating_point_matrix_coded", "integer_array_coded")


def _json_components(items, source) -> dict:
    out = {}
    for c in items or []:
        if not isinstance(c, dict) or "id" not in c:
            raise ConfigError(source, f"not a REXS file: a component must be an object with "
                              f"an id, got {str(c)[:60]!r}")
        attrs = {}
        for a in c.get("attributes", []) or []:
            kind = next((k for k in _JSON_KINDS if k in a), None)
            value = a.get(kind) if kind else None
            if kind and kind.endswith("_coded") and isinstance(value, dict):
                value = _decode(value.get("code", ""), value.get("value", ""))
            attrs[a.get("id")] = (value, a.get("unit", "") or "")
        out[str(c["id"])] = (c.get("type", ""), c.get("name", "") or "", attrs)
    return out


def _read_json(text: str, source: str):
    try:
        doc = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ConfigError(source, f"not a REXS file: not valid JSON ({exc})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("model"), dict):
        raise ConfigError(source, "not a REXS file: the JSON root must be an object with a "
                          "\"model\" object")
    m = doc["model"]
    comps = _json_components(m.get("components"), source)
    rels = [(str(r.get("id")), r.get("type", ""),
             tuple((x.get("role", ""), str(x.get("id")), x.get("hint", "") or "")
                   for x in r.get("refs", []) or []))
            for r in m.get("relations", []) or []]
    spectrum = m.get("load_spectrum") or {}
    cases = [{cid: attrs for cid, (_, _, attrs) in _json_components(lc.get("components"),
                                                                     source).items()}
             for lc in spectrum.get("load_cases", []) or []]
    return str(m.get("version", "")), m.get("applicationId", ""), comps, rels, cases


def read_rexs(path: str | Path) -> RexsModel:
    """Read a ``.rexs`` (XML) or ``.rexsj`` (JSON) file; ConfigError naming the file (and
    the component and attribute) for anything that is not a REXS model this reads."""
    p = Path(path)
    source = str(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise ConfigError(source, f"cannot read: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError:
        raise ConfigError(source, "not a REXS file: not UTF-8 text") from None
    head = text.lstrip()[:1]
    if head == "<":
        version, app, comps, rels, cases = _read_xml(text, source)
    elif head == "{":
        version, app, comps, rels, cases = _read_json(text, source)
    else:
        raise ConfigError(source, "not a REXS file: neither XML (<model ...>) nor JSON "
                          "({\"model\": ...})")
    if version not in SUPPORTED_VERSIONS:
        raise ConfigError(source, f"REXS version {version!r} is not supported; supported: "
                          f"{', '.join(SUPPORTED_VERSIONS)}")
    components = {cid: Component(cid, t, n, a) for cid, (t, n, a) in comps.items()}
    relations = tuple(Relation(i, t, refs) for i, t, refs in rels)
    for r in relations:
        for role, cid, _ in r.refs:
            if cid not in components:
                raise ConfigError(source, f"relation {r.id} ({r.type}) refers to component "
                                  f"{cid} as {role!r}, which the file does not define")
    for k, case in enumerate(cases):
        for cid in case:
            if cid not in components:
                raise ConfigError(source, f"load case {k + 1} refers to component {cid}, "
                                  "which the file does not define")
    return RexsModel(source, version, app or "", components, relations, tuple(cases))
