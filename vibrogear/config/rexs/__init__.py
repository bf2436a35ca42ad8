"""REXS import: a gear-design tool's REXS model (``.rexs`` XML, ``.rexsj`` JSON) as a scene.

:func:`import_rexs` reads the file (:mod:`.reader`), maps its components to scene tables
(:mod:`.mapping`, :mod:`.mapping_supports`, :mod:`.mapping_loads`) and returns the scene
data, the TOML text with comments naming each entry's REXS component, and the mapping
report (mapped / assumed / ignored).
"""
from __future__ import annotations

from .mapping import MappingReport, RexsImport, import_rexs, is_rexs_path

__all__ = ["import_rexs", "RexsImport", "MappingReport", "is_rexs_path"]
