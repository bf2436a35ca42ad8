"""Accuracy of the reduction (paper section II.B): the model's own error-against-run-time view.

1. Linearised reduced model against the linearised *full* model (all shaft DOF, all housing
   DOF, the same couplings in physical coordinates with the same tangent stiffnesses at the
   static state): undamped, non-rotating eigenfrequencies up to ``f_max_hz`` and the MAC on
   the shaft DOF plus the bore coupling points (where both models are defined).
2. Reduction levels (master-mode counts per shaft / housing): frequency error against the
   full model, the nonlinear time response's error against the largest level, and
   integrator time.  The response is the gear-mesh deformation of ``meshes[0]`` over the
   record window (after ``transient_periods``).  Where the largest level's motion is
   periodic (period-n from its stroboscopic samples) it is compared point by point
   (``response_error``, ``extrema_error``); where it is not (chaotic rattle: trajectories
   do not converge), only by statistics that do converge (``statistics_error``: the
   largest normalised difference of the RMS of the dynamic deformation, its spectral lines
   at 1x-3x the mesh frequency, impacts per period and the rattle intensity of
   ``meshes[0]``), with an error bar from batch means over blocks of the record
   (``statistics_error_bar``; :func:`~vibrogear.solvers.sequential.record_metrics.deformation_statistics`).
   ``judged_by`` says which.
3. With ``frequency_level``: the same for the level of the paper's frequency criterion, with
   and without the static correction (:mod:`vibrogear.models.gearbox.master_level`).

The full model's modes (the costly part: all housing DOF) are cached like the housing
(:func:`_full_reference`).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..status import Outcome
from .study import integration_options
from .study import start_state as _model_start

__all__ = ["run_reduction_accuracy", "full_linear_model", "reduced_linear_modes",
           "ReductionAccuracyResult"]


@dataclass(frozen=True, eq=False)
class ReductionAccuracyResult:
    """One row (dict) per count level (``rows``) and per frequency-criterion level
    (``extra``), with the full-vs-reduced mode ``pairs``; what
    :mod:`vibrogear.report.writers.reduction_accuracy` writes."""
    rows: tuple
    extra: tuple
    title: str


def _physical_vector_full(vec, offsets, hous_T, n_shafts) -> sp.csc_matrix:
    """A PhysicalVector as a sparse column over the full DOF (housing through T)."""
    n = int(offsets[-1])
    rows, vals = [], []
    for s, idx, val in vec.parts:
        if s < n_shafts:
            rows.extend(offsets[s] + idx)
            vals.extend(val)
        else:
            w = sp.csr_matrix((val, (np.zeros(len(idx), dtype=int), idx)),
                              shape=(1, hous_T.shape[0])) @ hous_T
            w = w.tocoo()
            rows.extend(offsets[s] + w.col)
            vals.extend(w.data)
    return sp.csc_matrix((vals, (rows, np.zeros(len(rows), dtype=int))), shape=(n, 1))


def full_linear_model(gm, scene, x0):
    """(FullLinearModel, observation operator (n_obs x n_full)) linearised at x0."""
    from ..models.gearbox.full_linear import assemble_full
    from ..models.housing.run import housing_matrices
    from ..solvers.linear import contact_slopes

    blocks = [(r.K, r.M) for r in gm.rotors]
    hm = None
    if scene.housing is not None:
        hm = housing_matrices(scene.housing)
        blocks.append((hm.K, hm.M))
    sizes = [b[0].shape[0] for b in blocks]
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    ns = len(gm.rotors)
    T = hm.T if hm is not None else None
    k_contacts, _ = contact_slopes(gm.reduced, x0)
    omega2 = gm.omega_ref ** 2
    terms = [(_physical_vector_full(l.vector, offsets, T, ns), l.stiffness)
             for l in gm.links if l.stiffness]
    terms += [(_physical_vector_full(c.vector, offsets, T, ns), k * omega2)
              for c, k in zip(gm.contacts, k_contacts) if k > 0]
    full = assemble_full(blocks, terms)
    # observation: all shaft DOF + the housing bore points
    n = int(offsets[-1])
    obs = [sp.identity(n, format="csr")[:offsets[ns]]]
    if T is not None:
        obs.append(sp.hstack([sp.csr_matrix((T.shape[0], offsets[ns])), T]).tocsr())
    return full, sp.vstack(obs).tocsr()


def reduced_linear_modes(gm, x0):
    """Undamped non-rotating modes of the linearised reduced model: (f_hz, observed
    vectors on the shaft DOF + housing bore points)."""
    import scipy.linalg as sla

    from ..solvers.linear import tangent_matrices

    K, _ = tangent_matrices(gm.reduced, x0, 0.0)
    lam, X = sla.eigh(0.5 * (K + K.T))
    f = np.sqrt(np.clip(lam, 0.0, None)) * gm.omega_ref / (2 * np.pi)
    from ..models.gearbox.synthesis import subsystem_offsets

    off = subsystem_offsets(gm.subsystems)
    parts = []
    for k, sub in enumerate(gm.subsystems):
        parts.append(sub.vectors @ X[off[k]:off[k + 1]])
    return f, np.vstack(parts)


def _compare(f_full, v_full, f_red, v_red, f_max):
    from scipy.optimize import linear_sum_assignment

    from ..models.gearbox.full_linear import mac_matrix

    keep = (f_full <= f_max) & (f_full > 1e-3 * f_max)
    fk = f_full[keep]
    mac = mac_matrix(v_full[:, keep], v_red)
    # one-to-one pairs of the largest total MAC: the per-mode argmax (pair_modes) can give
    # two reference modes one reduced mode (the unweighted MAC of rotation-dominated shaft
    # modes), and a 3 kHz mode paired with a 1 kHz one reports a 66 % frequency "error"
    match = dict(zip(*linear_sum_assignment(-mac)))
    pairs = [(i, int(match.get(i, np.argmax(mac[i])))) for i in range(fk.size)]
    return [{"f_full_hz": float(fk[i]), "f_reduced_hz": float(f_red[j]),
             "rel_error": float((f_red[j] - fk[i]) / fk[i]), "mac": float(mac[i, j])}
            for i, j in pairs]


def _start(gm, rpm: float) -> np.ndarray:
    return _model_start(gm.reduced, rpm)


#: dense samples per period of the recorded response
_SAMPLES = 32
#: converging statistics compared between levels (:func:`_statistics`)
STATISTICS = ("rms", "line_1x", "line_2x", "line_3x", "impacts", "rattle")


def _response(gm, scene, cfg):
    """(mesh deformation of meshes[0] at 32 samples per period over the record window,
    the record's trajectory, its statistics with batch-means errors, period_n, the
    outcomes of the integrations run: transient, record): the record starts after
    ``transient_periods`` at phase 0."""
    from ..solvers.integrator.contact_eval import contact_history
    from ..solvers.integrator.integrate import integrate
    from ..solvers.sequential.motion import classify_period
    from ..solvers.sequential.record_metrics import deformation_statistics

    r, rpm = gm.reduced, cfg.rpm
    # mesh periods of meshes[0] (the documented unit), the record rounded up to whole
    # excitation periods of P mesh periods (P > 1: torque orders or meshes at their own
    # frequencies)
    T, P = r.base_period(rpm), r.period_multiple
    opts = integration_options(scene, section=scene.reduction_accuracy)
    warm = integrate(r, rpm, _start(gm, rpm), 0.0, cfg.transient_periods * T, options=opts)
    if not warm.ok:
        return None, warm, {}, 0, [warm.outcome]
    R = -(-cfg.record_periods // P) * P
    # the record continues the forcing where the transient left it: the transient's base
    # periods modulo the forcing's common period (0 where the forcing repeats every base
    # period, as before; a restart at 0 would jump the phase of a torque order or of a mesh
    # at its own frequency)
    P_f = r.forcing_period_multiple
    t_w = float((cfg.transient_periods % P_f if P_f else cfg.transient_periods) * T)
    t_eval = np.arange(1, _SAMPLES * R + 1) * (T / _SAMPLES)
    t_eval[-1] = R * T
    t_eval = t_w + t_eval
    tr = integrate(r, rpm, warm.u_end, t_w, t_w + R * T, t_eval=t_eval, options=opts)
    if not tr.ok:
        return None, tr, {}, 0, [warm.outcome, tr.outcome]
    u = np.vstack([warm.u_end, tr.u])
    delta = contact_history(r, rpm, np.concatenate([[t_w], t_eval]), u)[0]
    n, _ = classify_period(tr.u[_SAMPLES - 1::_SAMPLES], min(8, R // 2), 1e-4,
                           split=r.n_modes)
    stats = deformation_statistics(delta[0, :-1], _SAMPLES, period_n=n)
    # the metrics count per base period of a window given in excitation periods P T
    stats.update(_contact_statistics(r, rpm, warm.u_end, tr, t_eval, P * T,
                                     n // P if n % P == 0 else n, opts, t_w))
    return delta[0], tr, stats, int(n), [warm.outcome, tr.outcome]


def _contact_statistics(r, rpm, start, tr, t_eval, T, n, opts, t_w: float = 0.0) -> dict:
    """Impacts per period (both flanks) and rattle intensity of meshes[0], with their
    batch-means errors (:func:`~vibrogear.solvers.sequential.record_metrics.metrics_with_errors`),
    over the record [t_w, t_eval[-1]] (model times)."""
    from ..models.contact_law import flank
    from ..solvers.integrator.contact_eval import contact_kinematics
    from ..solvers.sequential.record_metrics import contact_groups, metrics_with_errors
    from ..solvers.sequential.record_window import onset_speeds

    groups = contact_groups(r)
    key = next((k for k, (kind, _) in groups.items() if kind == "mesh"), None)
    if key is None:
        return {}
    rows = {int(groups[key][1][0])}
    speeds = onset_speeds(tr, rows)
    mode0 = flank(contact_kinematics(r, rpm, [t_w], start[None, :])[0][:, 0],
                  r.contacts.gap_hi, r.contacts.gap_lo)
    m = metrics_with_errors(r, {key: groups[key]}, mode0,
                            (tr.event_times, np.asarray(tr.event_contacts, int),
                             np.asarray(tr.event_modes, int)), np.array(speeds),
                            t_w, t_eval[-1], T, period_n=n)
    return {"impacts": m[f"impacts_drive_{key}"] + m[f"impacts_back_{key}"],
            "impacts_err": float(np.hypot(m[f"impacts_drive_{key}_err"],
                                          m[f"impacts_back_{key}_err"])),
            "rattle": m[f"rattle_{key}"], "rattle_err": m[f"rattle_{key}_err"]}


def _statistics_error(stats: dict, ref: dict) -> tuple[float, float, dict]:
    """(largest normalised difference of a statistic from the reference level's, its
    combined batch-means error bar, {statistic: (difference, error bar)}): the RMS
    relative to the reference's RMS, the spectral lines to its largest line, impacts per
    period to max(reference, 1), the rattle intensity to the reference's."""
    lines = max((ref.get(f"line_{h}x", 0.0) for h in (1, 2, 3)), default=0.0)
    norm = {"rms": ref.get("rms"), "impacts": max(ref.get("impacts", 0.0), 1.0),
            "rattle": ref.get("rattle") or None,
            **{f"line_{h}x": lines or None for h in (1, 2, 3)}}
    each = {}
    for k in STATISTICS:
        if k not in stats or k not in ref or not norm.get(k):
            continue
        d = abs(stats[k] - ref[k]) / norm[k]
        e = float(np.hypot(stats.get(f"{k}_err", np.nan), ref.get(f"{k}_err", np.nan))) / norm[k]
        if np.isfinite(d):
            each[k] = (float(d), e)
    if not each:
        return np.nan, np.nan, {}
    k = max(each, key=lambda q: each[q][0])
    return each[k][0], each[k][1], each


def _warm_up(gm, scene, cfg) -> Outcome:
    """One excitation period, to compile the integrator first; its outcome."""
    from ..solvers.integrator.integrate import integrate

    r = gm.reduced
    return integrate(r, cfg.rpm, _start(gm, cfg.rpm), 0.0, r.excitation_period(cfg.rpm),
                     options=integration_options(scene, section=scene.reduction_accuracy)).outcome


def _full_reference(gm, scene, x0, f_max_hz):
    """(f_full, observed vectors, full DOF, wall seconds, from_cache) of the full linearised
    model, cached (vibrogear.cache) under the gearbox and housing configs, f_max and the
    contact tangent stiffnesses of the linearisation (to 12 digits), as the housing is."""
    import dataclasses

    from ..cache import cache_key, discard_entry, new_workspace, open_entry, publish_entry
    from ..models.gearbox.full_linear import lowest_modes_full
    from ..solvers.linear import contact_slopes

    t0 = time.perf_counter()
    k_contacts, _ = contact_slopes(gm.reduced, x0)
    key = cache_key("reduction-full", {
        "gearbox": dataclasses.asdict(scene.gearbox),
        "housing": None if scene.housing is None else scene.housing.key_data(),
        "f_max_hz": float(f_max_hz), "contact_slopes": [f"{k:.12g}" for k in k_contacts]})
    folder = open_entry(key)
    if folder is not None:
        try:
            with np.load(folder / "full_reference.npz") as z:
                return (z["f_full"], z["v_full"], int(z["dofs"]), time.perf_counter() - t0,
                        True)
        except Exception as exc:                 # valid checksums, unreadable: another layout
            discard_entry(key, f"cannot be read: {exc}")
    full, obs = full_linear_model(gm, scene, x0)
    f_full, vec = lowest_modes_full(full, f_max_hz)
    v_full = obs @ vec
    work = new_workspace(key)
    np.savez(work / "full_reference.npz", f_full=f_full, v_full=v_full, dofs=full.n_dofs)
    publish_entry(work, key)
    return f_full, v_full, int(full.n_dofs), time.perf_counter() - t0, False


def _level_row(gm, scene, cfg, f_full, v_full, row):
    """Frequency error and MAC against the full model, and the nonlinear response; (row,
    response, the outcomes of the response's integrations)."""
    x0 = _start(gm, cfg.rpm)[:gm.reduced.n_modes]
    row["m"] = gm.reduced.n_modes
    row["f_top_hz"] = float(max(s.freqs_hz.max() for s in gm.subsystems))
    row["build_s"] = float(sum(gm.timings.values()))
    if f_full is not None and gm.reduced.n_modes:
        f_red, v_red = reduced_linear_modes(gm, x0)
        cmp = _compare(f_full, v_full, f_red, v_red, cfg.f_max_hz)
        row["modes_compared"] = len(cmp)
        row["max_freq_error"] = max((abs(c["rel_error"]) for c in cmp), default=np.nan)
        row["min_mac"] = min((c["mac"] for c in cmp), default=np.nan)
        row["pairs"] = cmp
    delta, tr, stats, n, solves = _response(gm, scene, cfg)
    sim = Outcome.combine(solves)                 # transient + record
    row["sim_wall_s"] = sim.wall_s
    row["steps"] = sim.counters["steps"]
    row["status"] = tr.message
    row["period_n"] = n
    row["statistics"] = stats
    return row, delta, solves


def run_reduction_accuracy(study, scene, ctx: RunContext) -> AnalysisOutcome:
    """The count levels of [reduction_accuracy], then (``frequency_level``) the level of
    the frequency criterion with and without the static correction
    (:mod:`vibrogear.models.gearbox.master_level`), each against the full model and, for the
    response, against the largest count level."""
    from ..models.gearbox.model import build_gearbox

    cfg = scene.reduction_accuracy
    t0 = time.perf_counter()
    levels = list(zip(cfg.shaft_counts, cfg.housing_counts))
    if scene.housing is None:
        levels = [(s, 0) for s, _ in levels]
    from .static_load import meet_loads        # each level carries the scene's torque

    def loaded(gm):
        return meet_loads(gm, scene.gearbox)[0]
    models = [loaded(build_gearbox(scene, master_counts=(s,) * len(scene.gearbox.shafts),
                                   housing_count=h or None)) for s, h in levels]
    full = f_full = v_full = None
    if cfg.full_model:
        gm = models[-1]
        x0 = _start(gm, cfg.rpm)[:gm.reduced.n_modes]
        f_full, v_full, dofs, full_wall, cached = _full_reference(gm, scene, x0, cfg.f_max_hz)
        full = {"dofs": dofs, "modes_below_f_max": int(np.sum(f_full <= cfg.f_max_hz)),
                "wall_s": full_wall, "from_cache": cached}
    rows, responses = [], []
    # every integration run, for the runner's solver entries
    solves = [_warm_up(models[0], scene, cfg)]   # compile first: the times compare solvers
    for (s, h), gm in zip(levels, models):
        row, delta, ran = _level_row(gm, scene, cfg, f_full, v_full,
                                {"level": "count", "shaft_modes": s, "housing_modes": h})
        solves += ran
        responses.append(delta)
        rows.append(row)
    extra = []
    if getattr(cfg, "frequency_level", False):
        h = levels[-1][1]
        for corr, name in ((True, "frequency"), (False, "frequency_no_static")):
            gm = loaded(build_gearbox(scene, housing_count=h or None, master_level="frequency",
                                      static_correction=corr))
            row, delta, ran = _level_row(gm, scene, cfg, f_full, v_full, {
                "level": name, "housing_modes": h,
                "shaft_modes": "+".join(str(sub.n_modes) for sub in gm.subsystems
                                        if sub.kind == "shaft")})
            solves += ran
            extra.append(row)
            responses.append(delta)
    ref_row = rows[-1]
    ref = responses[len(rows) - 1]
    periodic = ref_row.get("period_n", 0) > 0
    for row, delta in zip(rows + extra, responses):
        # pointwise errors only where the reference motion is periodic (a chaotic time
        # series does not converge pointwise): there the statistics judge the level
        row["judged_by"] = "pointwise" if periodic else "statistics"
        d, e, each = _statistics_error(row.get("statistics", {}),
                                       ref_row.get("statistics", {}))
        row["statistics_error"], row["statistics_error_bar"] = d, e
        row["statistics_errors"] = {k: {"error": v[0], "error_bar": v[1]}
                                    for k, v in each.items()}
        if delta is None or ref is None or not periodic or row.get("period_n") != \
                ref_row.get("period_n"):
            row["response_error"] = np.nan
            row["extrema_error"] = np.nan
            continue
        scale = np.max(np.abs(ref))
        row["response_error"] = float(np.max(np.abs(delta - ref)) / scale)
        row["extrema_error"] = float(max(abs(delta.max() - ref.max()),
                                         abs(delta.min() - ref.min())) / scale)
    if all(r_["status"] != "ok" for r_ in rows):
        raise NumericalFailure("reduction study: no level integrated successfully")
    result = ReductionAccuracyResult(
        rows=tuple(rows), extra=tuple(extra),
        title=f"{scene.scene.name}: reduction levels at {cfg.rpm:g} rpm")
    largest = rows[-1]
    strip = lambda r_: {k: v for k, v in r_.items() if k != "pairs"}  # noqa: E731
    summary = {"rpm": cfg.rpm, "f_max_hz": cfg.f_max_hz,
            "levels": [strip(r_) for r_ in rows],
            "frequency_levels": [strip(r_) for r_ in extra],
            "full_model": full,
            "wall_s": time.perf_counter() - t0,
            "error_estimate": {"max_freq_error_largest_level": largest.get("max_freq_error"),
                               "min_mac_largest_level": largest.get("min_mac"),
                               "judged_by": rows[-1]["judged_by"],
                               "response_error_second_largest":
                                   rows[-2]["response_error"] if len(rows) > 1 else None,
                               "statistics_error_second_largest":
                                   rows[-2]["statistics_error"] if len(rows) > 1 else None,
                               "statistics_error_bar_second_largest":
                                   rows[-2]["statistics_error_bar"] if len(rows) > 1
                                   else None}}
    return AnalysisOutcome(summary=summary, result=result, solver=Outcome.combine(solves))
