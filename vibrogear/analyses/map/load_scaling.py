"""The static load of a gearbox as one number: the transmitted input torque.

A gearbox's static load is the twist of its external couplings (``[[gearbox.couplings]]``,
role motor / load): coupling c applies the torque ``stiffness_c * twist_c`` to its shaft
(:func:`vibrogear.models.gearbox.model.external_couplings`).  The load enters the reduced model
only through the constant force ``forcing.F0``, which is linear in the twists.  With every
twist scaled by one factor ``s`` (the scene's load pattern kept):

    F0(s) = F0_rest + s * F0_couplings,

F0_couplings the coupling torques at the scene's twists projected on the model's own modal
basis, F0_rest = F0(scene) - F0_couplings the rest (gravity, free-gear drag), which does
not change.  The decomposition is exact (one projection, no second model build), and it
keeps the reduced basis fixed: for a scene whose basis does not depend on the load (master
modes by count, no static correction) it equals a model built with the scaled twists; with
the static correction (which adds the static deflection under the nominal load to the
basis) every load is computed in the nominal load's basis.

The map's twist is the first motor coupling's disc angle (the scene's twist x s).  Its torque is
the transmitted input torque the static state carries: the sum over the motor couplings of
stiffness x (s x disc angle - the shaft's static angle there), in the drive's sense, as the
load path states it.  Not stiffness x twist: where the motor and load couplings' twists do not
match the gear ratio (gear_pair: 2.5e3 N m/rad x 0.025 rad = 62.5 N m at the motor, 1e4 x
0.025 = 250 N m at the load, ratio 2), the static state settles between them and carries
90.98 N m.  The carried torque is affine in s (a constant part from gravity and free-gear
drag, which do not scale): T(s) = T(1) + (s - 1) (T(1) - T(1/2)) from the static states at
s = 1/2 and 1; a third at s = 3/2 checks it (``torque_law_error_rel``: gear_pair 0, its
meshes and couplings linear; two_stage 5e-4 and FVA 2e-4, from their Hertzian bearings).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ...config.base import ConfigError

__all__ = ["LoadScaling", "load_scaling", "carried_torque", "motor_couplings"]


def motor_couplings(gearbox_cfg) -> list[int]:
    """Indices of the couplings with role "motor"."""
    return [i for i, c in enumerate(gearbox_cfg.couplings) if c.role == "motor"]


#: the load scales whose static states fix the carried torque's affine law, and the one that
#: checks it
LAW_SCALES = (0.5, 1.0)
CHECK_SCALE = 1.5


@dataclass(frozen=True, eq=False)
class LoadScaling:
    """F0(s) = f0_rest + s * f0_couplings (model units); ``torque_nominal`` [N m, carried by
    the static state] and ``twist_nominal`` [rad, the first motor coupling's] at s = 1 (the
    scene's twists); ``torque_zero`` [N m]: the carried torque's constant part (T(0) of its
    affine law); ``torque_law_error_rel``: the law against the static state at s = 3/2."""
    f0_rest: np.ndarray
    f0_couplings: np.ndarray
    torque_nominal: float
    twist_nominal: float
    motor: str                      # name of the first motor coupling
    torque_zero: float = 0.0
    torque_law_error_rel: float = 0.0

    def scale_of_torque(self, torque) -> np.ndarray:
        return (np.asarray(torque, dtype=float) - self.torque_zero) / \
            (self.torque_nominal - self.torque_zero)

    def scale_of_twist(self, twist) -> np.ndarray:
        return np.asarray(twist, dtype=float) / self.twist_nominal

    def torque(self, scale) -> np.ndarray:
        return self.torque_zero + np.asarray(scale, dtype=float) * (self.torque_nominal
                                                                    - self.torque_zero)

    def twist(self, scale) -> np.ndarray:
        return np.asarray(scale, dtype=float) * self.twist_nominal

    def f0(self, scale: float) -> np.ndarray:
        return self.f0_rest + float(scale) * self.f0_couplings

    def model_at(self, model, scale: float):
        """``model`` (the scene's reduced model) with the load scaled by ``scale``."""
        forcing = dataclasses.replace(model.forcing, F0=self.f0(scale))
        return dataclasses.replace(model, forcing=forcing)


def load_scaling(gearbox_model, gearbox_cfg, path: str = "map") -> LoadScaling:
    """The decomposition of the scene's F0 (module docstring).  ConfigError (naming
    ``gearbox.couplings``) where the scene has no motor coupling, or its twist or stiffness
    is 0 so that no load can be scaled from it."""
    from ...models.gearbox.model import external_couplings
    from ...models.gearbox.synthesis import PhysicalVector, modal_vector

    motors = motor_couplings(gearbox_cfg)
    if not motors:
        raise ConfigError("gearbox.couplings", f"[{path}] scales the load of the motor "
                          "coupling: the scene needs a coupling with role = \"motor\"")
    first = gearbox_cfg.couplings[motors[0]]
    if not (first.static_twist > 0 and first.stiffness > 0):
        raise ConfigError(f"gearbox.couplings[{motors[0]}].twist", f"[{path}] scales the "
                          "scene's twists: the motor coupling needs twist > 0 and stiffness > "
                          f"0, got twist = {first.static_twist:g} rad, stiffness = {first.stiffness:g}")
    gm = gearbox_model
    if len(getattr(gm, "coupling_angles", ())) == len(gearbox_cfg.couplings):
        # the couplings' own parts of the static force (their disc angles as solved so
        # that a torque / power load is carried: vibrogear.analyses.static_load)
        couplings = PhysicalVector(gm.static_force.parts[:len(gearbox_cfg.couplings)])
    else:
        couplings = PhysicalVector.of(*external_couplings(gearbox_cfg, gm.rotors,
                                                          gm.shaft_ratios)[1])
    f0_c = modal_vector(couplings, gm.subsystems) / gm.omega_ref ** 2
    f0 = np.asarray(gm.reduced.forcing.F0, dtype=float)
    scaling = LoadScaling(f0_rest=f0 - f0_c, f0_couplings=f0_c, torque_nominal=math.nan,
                          twist_nominal=float(first.static_twist), motor=first.name)
    half, one = (carried_torque(gm, gearbox_cfg, scaling, s, path) for s in LAW_SCALES)
    slope = (one - half) / (LAW_SCALES[1] - LAW_SCALES[0])
    scaling = dataclasses.replace(scaling, torque_nominal=one, torque_zero=one - slope)
    check = carried_torque(gm, gearbox_cfg, scaling, CHECK_SCALE, path)
    return dataclasses.replace(scaling, torque_law_error_rel=float(
        abs(scaling.torque(CHECK_SCALE) - check) / max(abs(check), 1e-300)))


def carried_torque(gearbox_model, gearbox_cfg, scaling: LoadScaling, scale: float,
                   path: str = "map") -> float:
    """The transmitted input torque [N m] the static state carries with the load scaled by
    ``scale``: the sum over the motor couplings of stiffness x (scale x disc angle - the
    shaft's static angle), each in its drive's sense.  NumericalFailure naming the scale where
    the static state is not found."""
    from ...models.gearbox.load_path import coupling_signs, coupling_torques
    from ...pipeline.outcome import NumericalFailure
    from ...solvers.static import static_equilibrium

    st = static_equilibrium(scaling.model_at(gearbox_model.reduced, scale))
    if not st.converged:
        raise NumericalFailure(f"{path}: no static state at {scale:g} x the scene's load "
                               f"(the carried torque's law): {st.message}")
    torques = coupling_torques(gearbox_model, gearbox_cfg, st.x, scale)
    signs = coupling_signs(gearbox_cfg)
    return float(sum(signs[i] * torques[i] for i in motor_couplings(gearbox_cfg)))
