"""The sources of a gearbox's spectral lines, and each nvh steady point's lines and evidence.

Candidate sources at a driving speed n [rpm] (f_s = n / 60, speed ratios from
``GearboxConfig.speed_ratios``):

* ``mesh``: each mesh's tooth-pass frequency z_a |p_a| f_s, orders 1 .. :data:`MESH_ORDERS`;
* ``shaft``: each shaft's rotation |p_shaft| f_s, orders 1 .. :data:`SHAFT_ORDERS`;
* ``free gear``: each free gear's speed relative to its shaft |p_gear - p_shaft| f_s (what its
  own bearing sees), orders 1 .. :data:`SHAFT_ORDERS`;
* ``bearing``: each rolling-element bearing's cage (FTF), outer- and inner-race ball-pass
  frequencies (BPFO, BPFI) by the closed forms of
  :func:`~vibrogear.solvers.sequential.spectral_lines.bearing_frequencies`, inner race on the
  shaft, outer race fixed, contact angle 0 (radial ball and roller bearings).  A bearing
  given by designation, boundary dimensions or element set brings its own element count,
  element and pitch diameters (``GearboxBearingConfig.element_set``).  Otherwise the config
  gives the number of elements (the bearing's or the housing bore's ``rolling_elements``) but
  no ball and pitch diameters; they are taken from the journal diameter d (the shaft section
  at the bearing) and the bore diameter D (the housing bore; 2 d without one) by the
  catalogue proportions of deep-groove bearings, ball 0.3 (D - d), pitch (D + d) / 2 (an
  SKF 6207, d = 35, D = 72 mm: 11.1 and 53.5 mm, its catalogue values).  NB the model's
  rolling elements sit at fixed angles (no cage turns): the model has no mechanism that
  makes these lines; they are candidates so that a line that falls on one is named;
* ``mode``: the damped natural frequencies of the linearised model (the ``modes`` analysis,
  its indices as in ``modes.csv``), order 1.

The tolerance is half a frequency bin (the record's resolution).  Each line is named by
:func:`~vibrogear.solvers.sequential.spectral_lines.identify`; :func:`point_lines` adds the
point's evidence: the torus base pair (f1 = the excitation, f2 the line whose lattice
explains the most line power), the fraction of the AC power outside the identified lines
and the spectral flatness.
"""
from __future__ import annotations

import numpy as np

from ...solvers.sequential.spectral_lines import (CHANCE_MAX, THRESHOLD as THRESHOLD_REL, Source,
    base_pair, bearing_frequencies, broadband_fraction, coverage, find_lines, identify,
    spectral_flatness)

__all__ = ["gearbox_sources", "bearing_geometry", "natural_frequencies", "point_lines",
           "sweep_classes", "label_points", "sources_coverage",
           "MESH_ORDERS", "SHAFT_ORDERS", "BALL_FRACTION"]

#: mesh harmonics tried
MESH_ORDERS = 12
#: shaft and free-gear orders tried
SHAFT_ORDERS = 6
#: ball diameter / (D - d) of a deep-groove ball bearing (catalogue proportion)
BALL_FRACTION = 0.3


def _journal_diameter(shaft, position: float) -> float:
    """Outer diameter of the shaft section at ``position`` (the larger at a boundary)."""
    x, best = 0.0, 0.0
    for sec in shaft.sections:
        if x - 1e-12 <= position <= x + sec.length + 1e-12:
            best = max(best, sec.outer_diameter)
        x += sec.length
    return best or shaft.sections[0].outer_diameter


def bearing_geometry(scene) -> list[dict]:
    """Per rolling-element bearing: name, shaft index, elements, d_over_D (ball over pitch
    diameter) and how it was found (module docstring)."""
    cfg = scene.gearbox
    bores = {}
    housing = getattr(scene, "housing", None)
    for b in getattr(housing, "bores", ()) or ():
        bores[getattr(b, "name", "")] = b
    out = []
    for b in cfg.bearings:
        if b.type not in ("ball", "roller"):
            continue
        s = cfg.shaft_index(b.shaft, "")
        sh = cfg.shafts[s]
        d = _journal_diameter(sh, b.position)
        es = b.element_set()
        if es is not None:            # its own elements (designation, dimensions, element set)
            out.append({"name": b.name, "shaft": s, "elements": int(es.count),
                        "d_over_D": es.element_diameter / es.pitch_diameter,
                        "ball_m": es.element_diameter, "pitch_m": es.pitch_diameter,
                        "from": "the bearing's element set"})
            continue
        bore = bores.get(sh.bore)
        n = b.elements or (getattr(bore, "rolling_elements", None) if bore else None)
        if not n:
            continue
        D = 2.0 * bore.bore_radius if bore is not None else 2.0 * d
        ball, pitch = BALL_FRACTION * (D - d), 0.5 * (D + d)
        out.append({"name": b.name, "shaft": s, "elements": int(n), "d_over_D": ball / pitch,
                    "ball_m": ball, "pitch_m": pitch,
                    "from": "journal and housing bore" if bore is not None
                    else "journal, outer diameter 2 d assumed"})
    return out


def natural_frequencies(previous) -> tuple[np.ndarray, float]:
    """(damped natural frequencies [Hz] of the elastic modes, the speed they were computed
    at), from the ``modes`` outcome in ``previous``: the nvh verb needs it
    (``Verb.needs``), so the runner runs ``modes`` first where the scene does not."""
    prev = (previous or {}).get("modes")
    res = prev.result if prev is not None else None
    if res is None or not hasattr(res, "fd_hz"):
        raise LookupError("nvh needs the gearbox modes: call it through "
                          "vibrogear.analyses.invoke.with_needs (the verb registry's needs)")
    return np.asarray(res.fd_hz, dtype=float), float(res.rpm)


def gearbox_sources(scene, rpm: float, modes_hz=(), bearings=None) -> list[Source]:
    """The candidate sources (module docstring) at driving speed ``rpm``."""
    cfg = scene.gearbox
    fs = float(rpm) / 60.0
    shaft_p, gear_p = cfg.speed_ratios()
    out = []
    for m in cfg.meshes:
        a = cfg.gear_index(m.gear_a, "")
        out.append(Source(f"{m.name} mesh", cfg.gears[a].teeth * abs(gear_p[a]) * fs, "mesh",
                          MESH_ORDERS))
    for s, sh in enumerate(cfg.shafts):
        out.append(Source(f"{sh.name} shaft", abs(shaft_p[s]) * fs, "shaft", SHAFT_ORDERS))
    for k, g in enumerate(cfg.gears):
        if g.free:
            rel = abs(gear_p[k] - shaft_p[cfg.shaft_index(g.shaft, "")]) * fs
            out.append(Source(f"{g.name} relative", rel, "free gear", SHAFT_ORDERS))
    for b in (bearing_geometry(scene) if bearings is None else bearings):
        fr = abs(shaft_p[b["shaft"]]) * fs
        for key, f in bearing_frequencies(fr, b["elements"], b["d_over_D"]).items():
            if key != "BSF":
                out.append(Source(f"{b['name']} {key}", f, "bearing", 1))
    for i, f in enumerate(np.asarray(modes_hz, dtype=float)):
        out.append(Source(f"mode {i} ({f:.0f} Hz)", float(f), "mode", 1))
    return out


def point_lines(freq, amp, n_samples: int, sources, f1: float, *, torus: bool,
                max_hz: float | None = None) -> tuple:
    """(Lines, evidence dict) of one spectrum ``amp`` (K,) on ``freq`` (K,) [Hz]: its lines
    named by ``sources`` (tolerance half a bin, ``f1`` the excitation), with ``torus`` the
    base pair's f2 as a parent of the combination tones; the evidence: f1_hz, f2_hz, nu,
    explained (line power on the lattice), harmonic (on harmonics of f1 alone), broadband
    (AC power outside the identified lines), flatness (over the bins up to ``max_hz``),
    identified (line power named)."""
    freq = np.asarray(freq, dtype=float)
    tol = 0.5 * (freq[1] - freq[0])
    raw = find_lines(freq, amp)
    bp = base_pair(raw, f1, tol)
    base = [("f2", bp["f2"])] if torus and np.isfinite(bp["f2"]) else []
    lines = identify(raw, sources, tol, f1=f1, base=base)
    ident = lines.identified
    ev = {"f1_hz": float(f1), "f2_hz": float(bp["f2"]) if torus else float("nan"),
          "nu": float(bp["nu"]) if torus else float("nan"),
          "explained": float(bp["explained"]), "harmonic": float(bp["harmonic"]),
          "broadband": broadband_fraction(amp, n_samples, lines.bin[ident]),
          "flatness": spectral_flatness(amp, bins=None if max_hz is None else
                                        int(np.searchsorted(freq, max_hz)) + 1),
          "identified": lines.power_fraction(ident)}
    return lines, ev


def sources_coverage(sources, freq) -> dict:
    """Per kind, the chance that a line at a random frequency of the spectrum matches it."""
    freq = np.asarray(freq, dtype=float)
    return coverage(sources, 0.5 * (freq[1] - freq[0]), float(freq[-1]))


def sweep_classes(previous, direction: str, rpm) -> np.ndarray:
    """The motion class (``MOTION_LEGEND`` code) of the sweep point of ``direction`` at each
    speed of ``rpm``; -1 where no sweep ran before in this run or the speed is not one of
    its points."""
    out = np.full(np.size(rpm), -1, dtype=np.int64)
    prev = (previous or {}).get("sweep")
    if prev is None or getattr(prev.result.sweep, "motion_class", None) is None:
        return out
    res = prev.result.sweep
    for i, p in enumerate(np.atleast_1d(rpm)):
        k = np.flatnonzero((res.direction == direction) & (res.param == p))
        if k.size:
            out[i] = int(res.motion_class[k[0]])
    return out


def label_points(scene, rpm, f1_hz, freq_hz, amplitudes: dict, n_samples: int, classes,
                 modes_hz, max_hz: float) -> tuple[dict, dict, dict]:
    """Every steady point's lines and evidence: ({quantity: [Lines per point]} of the
    spectra (RSS over the channels), {evidence name: (P,) array} of the DTE spectrum, a
    summary).  ``classes``: the sweep's class per point (2 = quasi-periodic: its base pair
    is named), ``f1_hz`` (P,) the excitation, ``freq_hz`` (P, K), ``amplitudes``: quantity -> (P, channels, K)."""
    from ...solvers.sequential.motion import QUASI_PERIODIC

    geom = bearing_geometry(scene)
    lines = {q: [] for q, a in amplitudes.items() if a.ndim == 3 and a.shape[1]}
    ev: dict = {}
    chance = {}
    for i, p in enumerate(np.atleast_1d(rpm)):
        src = gearbox_sources(scene, float(p), modes_hz, geom)
        f1 = float(f1_hz[i])
        torus = int(classes[i]) == QUASI_PERIODIC
        for q in lines:
            rss = np.sqrt(np.sum(amplitudes[q][i] ** 2, axis=0))
            ln, e = point_lines(freq_hz[i], rss, n_samples, src, f1, torus=torus,
                                max_hz=max_hz)
            lines[q].append(ln)
            if q == "dte":
                for k, v in e.items():
                    ev.setdefault(k, []).append(v)
        if i == 0:
            chance = sources_coverage(src, freq_hz[i][freq_hz[i] <= max_hz])
    ev = {k: np.array(v, dtype=float) for k, v in ev.items()}
    summary = {"threshold_rel": THRESHOLD_REL, "tolerance": "half a bin",
               "chance_max": CHANCE_MAX, "bearings": geom,
               "modes": int(np.size(modes_hz)),
               "coverage_below_max_order": chance, "quantities": {}}
    for q, per in lines.items():
        kinds: dict = {}
        total = sum(float(np.sum(ln.amp ** 2)) for ln in per)
        for ln in per:
            for k, a in zip(ln.kind, ln.amp):
                kinds[k] = kinds.get(k, 0.0) + float(a) ** 2
        summary["quantities"][q] = {
            "lines": int(sum(ln.freq.size for ln in per)),
            "power_by_kind": {k: v / total for k, v in sorted(kinds.items())} if total else {}}
    return lines, ev, summary


def point_summary(rpm, classes, evidence: dict, lines, top: int = 5) -> list[dict]:
    """Per steady point: speed, the sweep's class, the evidence and its ``top`` strongest
    DTE lines [frequency Hz, amplitude m, source] (the summary's ``points_evidence``)."""
    from ...solvers.sequential.motion import MOTION_LEGEND

    out = []
    for i, p in enumerate(np.atleast_1d(rpm)):
        c = int(classes[i])
        row = {"rpm": float(p), "class": MOTION_LEGEND[c] if c >= 0 else None}
        row.update({k: float(v[i]) for k, v in evidence.items()})
        if lines is not None:
            ln = lines[i]
            k = np.argsort(ln.amp)[::-1][:top]
            row["strongest_lines"] = [[float(ln.freq[j]), float(ln.amp[j]), ln.source[j]]
                                      for j in k]
        out.append(row)
    return out
