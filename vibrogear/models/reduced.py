"""The reduced model: the one interface every solver sees.

A :class:`ReducedModel` is the second-order system in modal coordinates x (m of them)

    x'' + D x' + W x + P^T [ Bc(s) P x' + Kc(s) P x ] + sum_j c_j f_j(delta_j, delta_j') = F(t)

with D, W diagonal (modal damping and squared frequencies), the linear coupling kept
low-rank through P (r x m) and small dense Kc(s) = Kc0 + s Kc1, Bc(s) = Bc0 + s Bc1
(gyroscopic / circulatory terms scale with the spin s), and contact laws acting on
linear combinations of the state: delta_j = c_j . x - e_j(t) (e_j: kinematic
transmission error), delta_j' = c_j . x' - e_j'(t).  Each contact is a dead zone with
an upper gap g_hi and a lower gap g_lo (g_lo = -inf: one-sided):

    f_j = k_hi(t) (delta - g_hi)^p + c delta'         delta > g_hi   (mode +1)
    f_j = 0                                           g_lo <= delta <= g_hi (mode 0)
    f_j = -k_lo(t) (g_lo - delta)^p + c delta'        delta < g_lo   (mode -1)

with p = 1 (piecewise linear), 3/2 (Hertz, balls) or 10/9 (rollers) and
k(t) = k (1 + sum_h a_h cos(n_h W t) + b_h sin(n_h W t)) (periodic mesh stiffness).
Forcing F(t) = F0 + sum_h Fc_h cos(n_h W t) + Fs_h sin(n_h W t), with the base excitation
frequency W = omega_per_param * param and the spin s = spin_per_param * param, so one
scalar param (Omega for the impact pair, driving speed in rpm for a gearbox) moves
both.  The state is u = [x, x'] (length 2m).

The harmonic orders n_h (``harmonic_orders``) are 1, 2, ..., H unless given: a gearbox's
engine-order torque fluctuation adds slots at rational multiples of the mesh frequency
(order k of a shaft turning at p_s times the driving speed, W = z x the driving speed:
n = k p_s / z).  The
excitation is then periodic with period_multiple = P base periods, P the least common
denominator of the n_h, and ``excitation_period`` is that whole period P 2 pi / W: the
solvers that sample, shoot or settle over "a period" use the period of the forcing.  A
gearbox whose meshes excite at their own mesh frequencies adds slots h z_j p_j / (z_0 p_0)
of each mesh j; where the common period exceeds the model's ``period_limit`` (base periods),
the solvers sample, settle and count per base period instead (``period_multiple`` 1,
``multi_frequency`` True: the forcing does not repeat within a sampled period; its true
common period is ``forcing_period_multiple``, None when longer than MAX_PERIOD_MULTIPLE).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

__all__ = ["ReducedModel", "ContactSet", "LinearCoupling", "Forcing", "period_multiple",
           "MAX_PERIOD_MULTIPLE"]

#: the longest excitation period a model accepts, in base periods (a gearbox scene's own
#: limit, config.gearbox_supports.MAX_ORDER_PERIOD, is lower and named in its error)
MAX_PERIOD_MULTIPLE = 10_000


def period_multiple(orders) -> int:
    """P: the least common denominator of the harmonic orders (each a ratio of integers
    with a denominator <= MAX_PERIOD_MULTIPLE, to 1e-9 relative); ValueError otherwise."""
    P = 1
    for n in np.asarray(orders, dtype=float).ravel():
        f = Fraction(float(n)).limit_denominator(MAX_PERIOD_MULTIPLE)
        if not (n > 0 and abs(float(f) - n) <= 1e-9 * n):
            raise ValueError(f"harmonic order {n!r} is not a positive ratio of integers with "
                             f"a denominator <= {MAX_PERIOD_MULTIPLE}")
        P = P * f.denominator // math.gcd(P, f.denominator)
    if P > MAX_PERIOD_MULTIPLE:
        raise ValueError(f"the harmonic orders repeat only after {P} base periods "
                         f"(> {MAX_PERIOD_MULTIPLE})")
    return P


def _arr(a, shape=None, dtype=float) -> np.ndarray:
    out = np.ascontiguousarray(np.asarray(a, dtype=dtype))
    if shape is not None and out.shape != shape:
        raise ValueError(f"expected shape {shape}, got {out.shape}")
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class ContactSet:
    """nc contact laws acting on delta = directions @ x - e(t)."""
    directions: np.ndarray            # (nc, m)
    k_hi: np.ndarray                  # (nc,) stiffness beyond the upper gap
    k_lo: np.ndarray                  # (nc,) stiffness beyond the lower gap
    gap_hi: np.ndarray                # (nc,)
    gap_lo: np.ndarray                # (nc,) (-inf: one-sided)
    exponent: np.ndarray              # (nc,) 1, 1.5, 10/9
    damping: np.ndarray               # (nc,) viscous, only in contact
    stiffness_cos: np.ndarray         # (nc, H) relative mesh-stiffness harmonics
    stiffness_sin: np.ndarray         # (nc, H)
    error_cos: np.ndarray             # (nc, H) kinematic transmission error e(t)
    error_sin: np.ndarray             # (nc, H)
    names: tuple[str, ...] = ()

    @property
    def count(self) -> int:
        return self.directions.shape[0]

    @staticmethod
    def empty(m: int, n_harmonics: int) -> "ContactSet":
        z = np.zeros(0)
        zh = np.zeros((0, n_harmonics))
        return ContactSet(np.zeros((0, m)), z, z, z, z, z, z, zh, zh, zh, zh)


@dataclass(frozen=True, eq=False)
class LinearCoupling:
    """Low-rank linear coupling P^T (Kc P x + Bc P x'), Kc = Kc0 + s Kc1, Bc = Bc0 + s Bc1."""
    P: np.ndarray    # (r, m)
    Kc0: np.ndarray  # (r, r)
    Kc1: np.ndarray  # (r, r)
    Bc0: np.ndarray  # (r, r)
    Bc1: np.ndarray  # (r, r)

    @staticmethod
    def none(m: int) -> "LinearCoupling":
        z = np.zeros((0, 0))
        return LinearCoupling(np.zeros((0, m)), z, z, z, z)


@dataclass(frozen=True, eq=False)
class Forcing:
    """F(t) = F0 + sum_h Fc[h-1] cos(h W t) + Fs[h-1] sin(h W t)."""
    F0: np.ndarray   # (m,)
    Fc: np.ndarray   # (H, m)
    Fs: np.ndarray   # (H, m)


@dataclass(frozen=True, eq=False)
class ReducedModel:
    """First-order system u' = f(t, u; param), u = [x, x'] (see module docstring)."""
    omega2: np.ndarray             # (m,) diagonal stiffness (squared modal circular frequencies)
    damping: np.ndarray            # (m,) diagonal damping (2 zeta_i omega_i)
    coupling: LinearCoupling
    forcing: Forcing
    contacts: ContactSet
    omega_per_param: float = 1.0   # excitation circular frequency W = omega_per_param * param
    spin_per_param: float = 0.0    # spin s = spin_per_param * param
    monitor: int = 0               # contact whose deformation the analyses report
    name: str = "model"
    param_name: str = "Omega"
    state_names: tuple[str, ...] = field(default=())
    #: units of the model's variables: one model time unit in s, one force unit in N, and
    #: the displacement unit ("m"; "" for a nondimensional model such as the impact pair)
    time_unit_s: float = 1.0
    force_unit_n: float = 1.0
    length_unit: str = ""
    #: (H,) multiple of W of each harmonic slot (None: 1, 2, ..., H)
    harmonic_orders: np.ndarray | None = None
    #: the longest common excitation period [base periods] that the solvers span whole (None:
    #: no limit); beyond it they sample per base period (module docstring)
    period_limit: int | None = None

    def __post_init__(self):
        m = self.omega2.shape[0]
        H0 = self.forcing.Fc.shape[0]
        orders = np.arange(1.0, H0 + 1.0) if self.harmonic_orders is None \
            else self.harmonic_orders
        object.__setattr__(self, "harmonic_orders", _arr(orders, (H0,)))
        try:
            P = period_multiple(self.harmonic_orders)
        except ValueError:
            if self.period_limit is None:
                raise
            P = None            # no common period within MAX_PERIOD_MULTIPLE base periods
        object.__setattr__(self, "_forcing_period", P)
        whole = P is not None and (self.period_limit is None or P <= self.period_limit)
        object.__setattr__(self, "_period_multiple", P if whole else 1)
        object.__setattr__(self, "omega2", _arr(self.omega2, (m,)))
        object.__setattr__(self, "damping", _arr(self.damping, (m,)))
        H = self.forcing.Fc.shape[0]
        for name in ("Fc", "Fs"):
            _arr(getattr(self.forcing, name), (H, m))
        nc = self.contacts.count
        if self.contacts.directions.shape != (nc, m):
            raise ValueError("contact directions must be (nc, m)")
        if self.contacts.stiffness_cos.shape != (nc, H) or self.contacts.error_cos.shape != (nc, H):
            raise ValueError("contact harmonics must be (nc, H) with H = forcing harmonics")
        r = self.coupling.P.shape[0]
        if self.coupling.P.shape != (r, m):
            raise ValueError("coupling P must be (r, m)")
        if nc and not 0 <= self.monitor < nc:
            raise ValueError(f"monitor must index a contact (0..{nc - 1})")

    @property
    def n_modes(self) -> int:
        return self.omega2.shape[0]

    @property
    def n_states(self) -> int:
        return 2 * self.n_modes

    @property
    def n_harmonics(self) -> int:
        return self.forcing.Fc.shape[0]

    def excitation_frequency(self, param: float) -> float:
        return self.omega_per_param * param

    @property
    def period_multiple(self) -> int:
        """Base periods 2 pi / W in one period of the excitation (1 unless some harmonic
        order is fractional), the period the solvers sample, shoot and settle over; 1 where
        the common period exceeds ``period_limit`` (``multi_frequency``)."""
        return self._period_multiple

    @property
    def forcing_period_multiple(self) -> int | None:
        """The forcing's true common period in base periods (None: longer than
        MAX_PERIOD_MULTIPLE); equal to ``period_multiple`` unless ``multi_frequency``."""
        return self._forcing_period

    @property
    def multi_frequency(self) -> bool:
        """True where the solvers sample per base period of a forcing that does not repeat
        within it (its common period beyond ``period_limit``): a response that follows
        it is multi-frequency forced, and there is no periodic orbit to shoot."""
        return self._forcing_period != self._period_multiple

    def phase_time(self, periods: int, param: float) -> float:
        """The model time from which an integration ``periods`` excitation periods into a
        run continues the forcing where the last one left it: 0 where the forcing repeats
        every excitation period (every model the solvers span whole: integrations restart at
        0, exactly), else, for a multi-frequency model sampled per base period, the elapsed
        periods modulo the forcing's common period (all of them where that period is
        unknown) times the period.  Restarting such a model at 0 jumps the phase of every
        mesh whose frequency is not a multiple of the base one: a 0.8 % state error per
        restart on the FVA gearbox at 1602 rpm, and transients that read as a dynamic factor
        of 1.10 at 543 rpm (1.001 with the phase carried on)."""
        if not self.multi_frequency:
            return 0.0
        P = self.forcing_period_multiple
        n = int(periods) % P if P else int(periods)
        return float(n * self.excitation_period(param))

    def base_period(self, param: float) -> float:
        """2 pi / W: the mesh period of a gearbox (the excitation period unless a harmonic
        order is fractional)."""
        return 2.0 * np.pi / self.excitation_frequency(param)

    def excitation_period(self, param: float) -> float:
        """The period of the excitation: period_multiple base periods 2 pi / W."""
        return 2.0 * np.pi * self.period_multiple / self.excitation_frequency(param)
