"""The nominal torque balance of a gearbox scene's rigid gear train and its mesh roles
(no FE model): the structure part of :mod:`vibrogear.models.gearbox.load_path`, whose
docstring states the balance and the role rule."""
from __future__ import annotations

import numpy as np

from ...config.base import ConfigError

__all__ = ["mesh_roles", "coupling_signs", "mesh_arms", "nominal_torques"]

def _body_of_gear(cfg) -> list[int]:
    """Torsional body of each gear: its shaft's index, or len(shafts) + k for free gear k."""
    out, nfree = [], 0
    for g in cfg.gears:
        if g.free:
            out.append(len(cfg.shafts) + nfree)
            nfree += 1
        else:
            out.append(cfg.shaft_index(g.shaft, ""))
    return out


def _n_bodies(cfg) -> int:
    return len(cfg.shafts) + sum(1 for g in cfg.gears if g.free)


def _components(n: int, edges) -> list[int]:
    comp = list(range(n))

    def find(a):
        while comp[a] != a:
            comp[a] = comp[comp[a]]
            a = comp[a]
        return a
    for a, b in edges:
        comp[find(a)] = find(b)
    return [find(a) for a in range(n)]


def mesh_roles(cfg) -> list[str]:
    """``"loaded"`` or ``"idle"`` per mesh (module docstring: on a torque path between a
    motor and a load coupling, or not)."""
    body = _body_of_gear(cfg)
    n = _n_bodies(cfg)
    edges = [(body[cfg.gear_index(m.gear_a, "")], body[cfg.gear_index(m.gear_b, "")])
             for m in cfg.meshes]
    motors = {cfg.shaft_index(c.shaft, "") for c in cfg.couplings if c.role == "motor"}
    loads = {cfg.shaft_index(c.shaft, "") for c in cfg.couplings if c.role == "load"}
    roles = []
    for j, (a, b) in enumerate(edges):
        comp = _components(n, [e for i, e in enumerate(edges) if i != j])
        ca, cb = comp[a], comp[b]
        side = lambda c, group: any(comp[s] == c for s in group)  # noqa: E731
        if ca != cb:
            on_path = ((side(ca, motors) and side(cb, loads))
                       or (side(cb, motors) and side(ca, loads)))
        else:                      # on a loop: loaded when the loop joins a motor and a load
            on_path = side(ca, motors) and side(ca, loads)
        roles.append("loaded" if on_path else "idle")
    return roles


def coupling_signs(cfg) -> list[float]:
    """Sign of each coupling's static torque on its shaft's torsional DOF (a motor drives
    in the sense of rotation, a load brakes)."""
    shaft_p, _ = cfg.speed_ratios()
    return [(1.0 if shaft_p[cfg.shaft_index(c.shaft, "")] > 0 else -1.0)
            * (1.0 if c.role == "motor" else -1.0) for c in cfg.couplings]


def mesh_arms(gm) -> list[tuple[float, float, int, int]]:
    """Per mesh contact (in the scene's mesh order): (arm on gear_a, arm on gear_b, subsystem
    of a, subsystem of b), the arms the torsional entries of the contact vector [m]."""
    out = []
    for c in gm.contacts:
        if c.kind != "mesh":
            continue
        (sa, _, va), (sb, _, vb) = c.vector.parts[:2]
        out.append((float(va[5]), float(vb[5]), int(sa), int(sb)))
    return out


def nominal_torques(cfg, arms, produced: dict | None = None):
    """The nominal torque balance (module docstring): (mesh normal forces F_j [N, signed as
    the contact force], coupling torques [N m, signed on their DOF], notes).  ``arms``
    per mesh (arm_a, arm_b) [m]; ``produced``: {coupling index: static signed torque} for the
    couplings given by twist.  ConfigError where the given torques disagree with the ratios."""
    produced = produced or {}
    body = _body_of_gear(cfg)
    nb, nm, nc = _n_bodies(cfg), len(cfg.meshes), len(cfg.couplings)
    sign = coupling_signs(cfg)
    known = {i: sign[i] * c.static_torque for i, c in enumerate(cfg.couplings)
             if c.load_given in ("torque", "power")}
    notes = []
    if not known:
        motor = next((i for i, c in enumerate(cfg.couplings) if c.role == "motor"), None)
        if motor is not None and motor in produced:
            known[motor] = produced[motor]
            notes.append(f"the couplings give twists: the nominal input torque is the "
                         f"{abs(produced[motor]):.6g} N m the twist of "
                         f"{cfg.couplings[motor].name!r} "
                         "produces in the static state")
    A_mesh = np.zeros((nb, nm))
    for j, m in enumerate(cfg.meshes):
        A_mesh[body[cfg.gear_index(m.gear_a, "")], j] -= arms[j][0]
        A_mesh[body[cfg.gear_index(m.gear_b, "")], j] -= arms[j][1]
    C = np.zeros((nb, nc))
    for i, c in enumerate(cfg.couplings):
        C[cfg.shaft_index(c.shaft, ""), i] = 1.0
    unknown = [i for i in range(nc) if i not in known]
    while True:
        A = np.hstack([A_mesh, C[:, unknown]])
        rhs = -C[:, list(known)] @ np.array(list(known.values())) if known else np.zeros(nb)
        sol, *_ = np.linalg.lstsq(A, rhs, rcond=None)
        rank = np.linalg.matrix_rank(A) if A.size else 0
        twist_unknown = [i for i in unknown if i in produced]
        if rank >= A.shape[1] or not twist_unknown:
            break
        i = twist_unknown[-1]              # undetermined split: the twist's own torque
        known[i] = produced[i]
        unknown.remove(i)
    scale = max([abs(v) for v in known.values()] + [1e-30])
    resid = A @ sol - rhs
    if known and np.max(np.abs(resid)) > 1e-3 * scale:
        given = [i for i in known if cfg.couplings[i].load_given in ("torque", "power")]
        motors = [i for i in given if cfg.couplings[i].role == "motor"] or given[:1]
        if not any(c.role == "load" for c in cfg.couplings):
            c = cfg.couplings[motors[0]]
            raise ConfigError("gearbox.couplings", f"the torque of motor {c.name!r} "
                              f"({c.static_torque:.6g} N m) reaches no output: the scene has "
                              "no coupling with role = \"load\"; add one on the output shaft")
        loads = [i for i in given if i not in motors]
        shaft_p, _ = cfg.speed_ratios()
        ratio = {i: abs(shaft_p[cfg.shaft_index(cfg.couplings[motors[0]].shaft, "")]
                        / shaft_p[cfg.shaft_index(cfg.couplings[i].shaft, "")]) for i in loads}
        desc = "; ".join(f"load {cfg.couplings[i].name!r} {cfg.couplings[i].static_torque:.6g} "
                         f"N m (the ratio {ratio[i]:.6g} makes it "
                         f"{cfg.couplings[motors[0]].static_torque * ratio[i]:.6g} N m)"
                         for i in loads) if len(loads) == 1 else ", ".join(
                             f"{cfg.couplings[i].name!r} {cfg.couplings[i].static_torque:.6g} N m"
                             for i in loads)
        i0 = loads[0] if loads else motors[0]
        raise ConfigError(f"gearbox.couplings[{i0}].{cfg.couplings[i0].load_given}",
                          f"motor {cfg.couplings[motors[0]].name!r} "
                          f"{cfg.couplings[motors[0]].static_torque:.6g} N m and {desc} "
                          "disagree with the gear ratios (lossless torque balance); give the "
                          "load's torque as the motor's times the ratio, or one of them as a "
                          "twist")
    F = sol[:nm]
    T = np.zeros(nc)
    for i, v in known.items():
        T[i] = v
    for k, i in enumerate(unknown):
        T[i] = sol[nm + k]
    roles = mesh_roles(cfg)
    F = np.where(np.array(roles) == "idle", 0.0, F)
    return F, T, notes


