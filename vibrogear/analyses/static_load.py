"""The static load path of a gearbox scene before any dynamics (``docs/gearbox.md``, "The
static load path").

1. Rigid-body modes: the structure without its meshes (shafts, bearings, links, couplings)
   must hold every shaft in every direction along which the load works.  The null space of
   its assembled static stiffness is computed in the reduced coordinates (only rigid-body
   coordinates can span it: the elastic ones carry their own stiffness); a null vector along
   which the load (the couplings' torques and the meshes' nominal tooth forces) does work is
   a ConfigError naming the shaft, the direction and the bearings to fix.
2. The load carried: a coupling given by ``torque`` or ``power`` gets the disc angle that
   makes the static state of the elastic model carry that torque (Newton on the angles, the
   Jacobian from the tangent stiffness at the static state); one coupling keeps its angle
   (the first given by twist, else the first motor): the train's rigid rotation is free.
   The couplings' stiffness and damping, the modes and the frame are unchanged: only the
   constant load F0 changes.
3. The load path (:mod:`vibrogear.models.gearbox.load_path`) and its checks: a load that does
   not reach the output, a loaded mesh carrying less than half its nominal tooth force.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..config.base import ConfigError
from ..models.gearbox.load_path import (LoadPath, assumed_from_scene_text, compute_load_path,
                                        coupling_dofs, coupling_signs, coupling_torques,
                                        mesh_arms, nominal_torques, with_coupling_angles)
from ..models.gearbox.synthesis import PhysicalVector, modal_vector
from ..solvers.static import static_equilibrium, static_forces

__all__ = ["StaticLoad", "meet_loads", "static_load", "reference_rpm", "rigid_body_check",
           "rigid_housing", "UNDERLOAD_LIMIT"]

#: a loaded mesh carrying less than this fraction of its nominal tooth force is an error
UNDERLOAD_LIMIT = 0.5
#: relative torque tolerance of the angle solve (the issue's 0.1 %, with margin)
TORQUE_TOL = 1e-6


@dataclass(frozen=True, eq=False)
class StaticLoad:
    model: object              # GearboxModel, its coupling angles solved
    static: object             # StaticResult of model.reduced
    load_path: LoadPath
    iterations: int = 0


def reference_rpm(scene) -> float | None:
    """The driving-shaft speed [rpm] at which powers are stated: a coupling's power rpm
    (its shaft's speed, over the speed ratio), else [time_response] rpm, else the upper end
    of [sweep] / [continuation]."""
    cfg = scene.gearbox
    shaft_p, _ = cfg.speed_ratios()
    for c in cfg.couplings:
        if c.power is not None and c.rpm:
            return float(c.rpm / abs(shaft_p[cfg.shaft_index(c.shaft, "")]))
    tr = getattr(scene, "time_response", None)
    if tr is not None and getattr(tr, "param", None):
        return float(tr.param)
    for sec in ("sweep", "continuation"):
        v = getattr(getattr(scene, sec, None), "param_max", None)
        if v:
            return float(v)
    return None


def meet_loads(gm, cfg, *, max_iter: int = 25):
    """(model, static result, iterations): the torque / power couplings' disc angles solved
    so that the static state carries their torques (module docstring, 2)."""
    st = static_equilibrium(gm.reduced, 0.0)
    targets = [i for i, c in enumerate(cfg.couplings) if c.load_given in ("torque", "power")]
    if not targets or len(cfg.couplings) < 2:
        return gm, st, 0
    twist = [i for i, c in enumerate(cfg.couplings) if c.load_given == "twist"]
    if twist:
        free = targets
    else:
        ref = next((i for i in targets if cfg.couplings[i].role == "motor"), targets[0])
        free = [i for i in targets if i != ref]
    sign = coupling_signs(cfg)
    target = np.array([sign[i] * cfg.couplings[i].static_torque for i in free])
    k = np.array([cfg.couplings[i].stiffness for i in free])
    v = [modal_vector(PhysicalVector.of((s, [d], [1.0])), gm.subsystems)
         for s, d in coupling_dofs(cfg, gm)]
    V = np.array([v[i] for i in free]).T                      # (m, n free)
    angles = np.array(gm.coupling_angles, dtype=float)
    scale = max(float(np.max(np.abs(target))), 1e-30)
    it = 0
    for it in range(1, max_iter + 1):
        if not st.converged:
            break
        err = target - coupling_torques(gm, cfg, st.x)[free]
        if np.max(np.abs(err)) <= TORQUE_TOL * scale:
            it -= 1
            break
        _, J = static_forces(gm.reduced, st.x, 0.0)
        rhs = V * (k / gm.omega_ref ** 2)                     # dF0 / d angle, model units
        try:
            dx = np.linalg.solve(J, rhs)
        except np.linalg.LinAlgError:
            dx = np.linalg.lstsq(J, rhs, rcond=None)[0]
        D = np.diag(k) - k[:, None] * (V.T @ dx)              # d torque / d angle
        angles[free] += np.linalg.lstsq(D, err, rcond=None)[0]
        gm = with_coupling_angles(gm, cfg, angles)
        st = static_equilibrium(gm.reduced, 0.0, x0=st.x)
    return gm, st, it


def _physical_load(gm, cfg, F_nom) -> dict[int, np.ndarray]:
    """Per shaft (subsystem index): the static load on its FE DOF [N, N m]: the static force
    (coupling torques, weight, drag) and the meshes' nominal tooth forces."""
    out: dict[int, np.ndarray] = {}

    def add(vec, scale):
        for s, idx, val in vec.parts:
            if s >= len(gm.rotors):
                continue
            f = out.setdefault(s, np.zeros(gm.rotors[s].n_dofs))
            np.add.at(f, idx, scale * val)
    add(gm.static_force, 1.0)
    meshes = [c for c in gm.contacts if c.kind == "mesh"]
    for c, F in zip(meshes, F_nom):
        add(c.vector, -F)
    return out


_DIRECTIONS = {"u": "radially", "v": "radially", "w": "axially", "phi": "in tilt",
               "theta": "in tilt", "psi": "in rotation"}


def rigid_body_check(gm, cfg) -> None:
    """ConfigError where the structure without its meshes has a rigid-body mode along which
    the load works (module docstring, 1)."""
    r = gm.reduced
    rigid = np.nonzero(r.omega2 <= 1e-12 * max(float(np.max(r.omega2, initial=0.0)), 1e-30))[0]
    if not rigid.size:
        return
    K = np.zeros((r.n_modes, r.n_modes))
    cp = r.coupling
    if cp.P.shape[0]:
        K += cp.P.T @ (cp.Kc0 @ cp.P)
    ct = r.contacts
    bearing = [j for j, c in enumerate(gm.contacts) if c.kind == "bearing"]
    if bearing:
        d = ct.directions[bearing]
        kl = ct.k_hi[bearing] * (1e-5 ** (ct.exponent[bearing] - 1.0))   # secant at 10 um
        K += d.T @ (kl[:, None] * d)
    Krr = 0.5 * (K[np.ix_(rigid, rigid)] + K[np.ix_(rigid, rigid)].T)
    lam, Z = np.linalg.eigh(Krr)
    tol = 1e-9 * max(float(np.max(np.abs(lam), initial=0.0)), 1e-30)
    null = Z[:, lam <= tol]
    if not null.shape[1]:
        return
    arms = [a[:2] for a in mesh_arms(gm)]
    produced = {i: s * c.static_torque for i, (s, c) in
                enumerate(zip(coupling_signs(cfg), cfg.couplings))}
    F_nom, _, _ = nominal_torques(cfg, arms, produced)
    load = _physical_load(gm, cfg, F_nom)
    offsets = np.concatenate([[0], np.cumsum([s.n_modes for s in gm.subsystems])])
    from ..models.rotor.model import DOF_NAMES
    worst = None
    scale = max([float(np.max(np.abs(f))) for f in load.values()] + [1e-30])
    for col in null.T:
        x = np.zeros(r.n_modes)
        x[rigid] = col
        qs = {s: gm.subsystems[s].vectors @ x[offsets[s]:offsets[s + 1]] for s in load}
        amp = max([float(np.max(np.abs(q))) for q in qs.values() if q.size] + [0.0])
        if amp == 0.0:
            continue
        for s, f in load.items():
            q = qs[s]
            for t, name in enumerate(DOF_NAMES):
                work = abs(float(f[t::6][:gm.rotors[s].n_nodes] @ q[t::6][:gm.rotors[s].n_nodes]))
                work /= amp
                if work > 1e-6 * scale and (worst is None or work > worst[0]):
                    worst = (work, s, name)
    if worst is None:
        return
    _, s, dof = worst
    sh = cfg.shafts[s].name
    on = [b.name for b in cfg.bearings if b.shaft == sh or b.outer_shaft == sh]
    direction = _DIRECTIONS[dof]
    blist = ", ".join(repr(b) for b in on) or "none"
    if direction == "axially":
        fix = (f"give bearing {on[0]!r} an axial stiffness (axial_stiffness [N/m], the "
               "locating bearing)" if on else "add a bearing with an axial stiffness")
        cause = "no bearing takes axial load"
    elif direction == "in rotation":
        cause = "no coupling or loaded mesh holds it in rotation"
        fix = "add a load coupling on it or mesh it with a loaded gear"
    else:
        cause = f"its bearings ({blist}) do not hold it {direction}"
        fix = "give it a bearing (or bearing stiffness) that does"
    k = next(i for i, b in enumerate(cfg.shafts) if b.name == sh)
    raise ConfigError(f"gearbox.shafts[{k}]", f"shaft {sh!r} is free {direction}: {cause} "
                      f"(bearings on it: {blist}), and the static load (the couplings' torque "
                      f"through the meshes) moves it that way; {fix}")


def rigid_housing(scene):
    """``scene`` with its housing rigid (what `check` uses: it builds no housing FE model):
    every shaft's axis at its bore's, every bearing to ground with its bore's rolling
    elements where it gives none.  The torque path, the tooth forces and the bearings' total
    reactions are the housing scene's; the share between the bearings may differ."""
    from dataclasses import replace

    from ..config.model.layout import shaft_bore

    if scene.housing is None:
        return scene
    cfg = scene.gearbox
    bores = {sh.name: shaft_bore(scene.housing, sh.bore) for sh in cfg.shafts}
    shafts = tuple(replace(sh, bore="", x=bores[sh.name].x, z=bores[sh.name].z)
                   for sh in cfg.shafts)
    bearings = tuple(b if b.outer_shaft or b.elements is not None or b.type == "spring"
                     else replace(b, elements=bores[b.shaft].rolling_elements)
                     for b in cfg.bearings)
    return replace(scene, housing=None, gearbox=replace(cfg, shafts=shafts, bearings=bearings))


def _scene_assumed(source) -> tuple[dict, ...]:
    if not source:
        return ()
    try:
        return assumed_from_scene_text(Path(source).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError):
        return ()


def static_load(scene, gm=None, *, source: str | None = None, check: bool = True) -> StaticLoad:
    """Build (unless ``gm`` is given) the scene's gearbox model, check its rigid-body modes,
    solve the couplings' angles, compute the load path and check it (ConfigError naming the
    cause and the fix where the load does not pass)."""
    cfg = scene.gearbox
    if gm is None:
        from ..models.gearbox.model import build_gearbox
        gm = build_gearbox(scene)
    if check:
        rigid_body_check(gm, cfg)
    gm, st, its = meet_loads(gm, cfg)
    if check and not st.converged:
        raise ConfigError("gearbox", f"the static state under the scene's load was not found "
                          f"({st.message}; force residual {st.residual:.3g}): check that every "
                          "shaft is held by bearings and every loaded mesh can close")
    lp = compute_load_path(gm, cfg, st.x, scene=scene, reference_rpm=reference_rpm(scene),
                           assumed=_scene_assumed(source))
    if check:
        _check_path(cfg, lp)
    return StaticLoad(model=gm, static=st, load_path=lp, iterations=its)


def _check_path(cfg, lp: LoadPath) -> None:
    motors = [c for c in lp.couplings if c["role"] == "motor"]
    loads = [(i, c) for i, c in enumerate(lp.couplings) if c["role"] == "load"]
    given = [c for c in motors if c["given"] in ("torque", "power") and c["nominal_torque_Nm"] > 0]
    if given and not loads:
        raise ConfigError("gearbox.couplings", f"the torque of motor {given[0]['name']!r} "
                          f"({given[0]['nominal_torque_Nm']:.6g} N m) reaches no output: the "
                          "scene has no coupling with role = \"load\"; add one on the output "
                          "shaft")
    for i, c in loads:
        if c["nominal_torque_Nm"] > 0 and c["torque_Nm"] < UNDERLOAD_LIMIT * c["nominal_torque_Nm"]:
            raise ConfigError(f"gearbox.couplings[{i}]", f"the load does not reach the output: "
                              f"coupling {c['name']!r} on shaft {c['shaft']!r} carries "
                              f"{c['torque_Nm']:.4g} N m of its nominal "
                              f"{c['nominal_torque_Nm']:.4g} "
                              "N m; check the meshes and bearings between the motor and it")
    for j, m in enumerate(lp.meshes):
        if m.role == "loaded" and m.nominal_normal_force_N > 0 and \
                m.normal_force_N < UNDERLOAD_LIMIT * m.nominal_normal_force_N:
            mc = cfg.meshes[j]
            shafts = {cfg.gears[cfg.gear_index(g, "")].shaft for g in (mc.gear_a, mc.gear_b)}
            raise ConfigError(f"gearbox.meshes[{j}]", f"mesh {m.name!r} carries "
                              f"{m.normal_force_N:.4g} N of its nominal tooth force "
                              f"{m.nominal_normal_force_N:.4g} N (less than "
                              f"{UNDERLOAD_LIMIT:.0%}): the load bypasses it; check its stiffness "
                              "against any mesh in parallel with it, the bearings of shafts "
                              f"{', '.join(repr(s) for s in sorted(shafts))} (a support that "
                              "gives way lets the gears separate) and its backlash")
