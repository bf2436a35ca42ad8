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

The transmitted input torque is the sum over the motor couplings of stiffness x twist; the
map's twist is the first motor coupling's.  (two_stage: 2.5e3 N m/rad x 0.025 rad =
62.5 N m.)
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ...config.base import ConfigError

__all__ = ["LoadScaling", "load_scaling", "input_torque", "motor_couplings"]


def motor_couplings(gearbox_cfg) -> list[int]:
    """Indices of the couplings with role "motor"."""
    return [i for i, c in enumerate(gearbox_cfg.couplings) if c.role == "motor"]


def input_torque(gearbox_cfg, scale: float = 1.0) -> float:
    """Transmitted input torque [N m] with every twist scaled by ``scale``: sum over the
    motor couplings of stiffness x twist."""
    return float(scale * sum(gearbox_cfg.couplings[i].stiffness * gearbox_cfg.couplings[i].static_twist
                             for i in motor_couplings(gearbox_cfg)))


@dataclass(frozen=True, eq=False)
class LoadScaling:
    """F0(s) = f0_rest + s * f0_couplings (model units); ``torque_nominal`` [N m] and
    ``twist_nominal`` [rad, the first motor coupling's] at s = 1 (the scene's twists)."""
    f0_rest: np.ndarray
    f0_couplings: np.ndarray
    torque_nominal: float
    twist_nominal: float
    motor: str                      # name of the first motor coupling

    def scale_of_torque(self, torque) -> np.ndarray:
        return np.asarray(torque, dtype=float) / self.torque_nominal

    def scale_of_twist(self, twist) -> np.ndarray:
        return np.asarray(twist, dtype=float) / self.twist_nominal

    def torque(self, scale) -> np.ndarray:
        return np.asarray(scale, dtype=float) * self.torque_nominal

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
    torque = input_torque(gearbox_cfg)
    if not (first.static_twist > 0 and torque > 0):
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
    return LoadScaling(f0_rest=f0 - f0_c, f0_couplings=f0_c, torque_nominal=torque,
                       twist_nominal=float(first.static_twist), motor=first.name)
