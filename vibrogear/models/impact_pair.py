"""The impact pair of the paper (Fig. 3, eqs (12)-(15)) as a one-mode ReducedModel.

q'' + 2 zeta q' + kappa q + g(q) = f_m + f_p cos(Omega tau), with g the dead zone
(1 - kappa)(q -+ b_r) outside |q| <= b_r.  State u = [q, dq/dtau]; param = Omega.
"""
from __future__ import annotations

import numpy as np

from ..config.options import OMEGA
from .reduced import ContactSet, Forcing, LinearCoupling, ReducedModel

__all__ = ["impact_pair_model"]


def impact_pair_model(zeta: float, kappa: float, f_m: float, f_p: float, b_r: float,
                      contact_damping: float = 0.0) -> ReducedModel:
    one = np.ones(1)
    contacts = ContactSet(
        directions=np.ones((1, 1)),
        k_hi=(1.0 - kappa) * one, k_lo=(1.0 - kappa) * one,
        gap_hi=b_r * one, gap_lo=-b_r * one,
        exponent=one.copy(), damping=contact_damping * one,
        stiffness_cos=np.zeros((1, 1)), stiffness_sin=np.zeros((1, 1)),
        error_cos=np.zeros((1, 1)), error_sin=np.zeros((1, 1)),
        names=("clearance",),
    )
    forcing = Forcing(F0=np.array([f_m]), Fc=np.array([[f_p]]), Fs=np.zeros((1, 1)))
    return ReducedModel(
        omega2=np.array([kappa]), damping=np.array([2.0 * zeta]),
        coupling=LinearCoupling.none(1), forcing=forcing, contacts=contacts,
        omega_per_param=1.0, spin_per_param=0.0, monitor=0, name="impact_pair",
        param_name=OMEGA.name, state_names=("q", "dq/dtau"),
    )


def impact_pair_from_config(cfg) -> ReducedModel:
    """Build from an :class:`~vibrogear.config.sections.common.ImpactPairConfig`."""
    return impact_pair_model(cfg.zeta, cfg.kappa, cfg.f_m, cfg.f_p, cfg.b_r, cfg.contact_damping)


__all__.append("impact_pair_from_config")
