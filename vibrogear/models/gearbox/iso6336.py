"""Mesh stiffness of a cylindrical gear pair from its geometry: ISO 6336-1:2006, method B.

Pure numpy, SI units throughout (stiffness per face width in N/m^2: 1 N/(mm um) = 1e9 N/m^2).
External spur and helical pairs; both gears share the normal module ``mn``, the normal
pressure angle ``alpha_n`` and the helix angle ``beta`` (of the reference cylinder).

* virtual numbers of teeth ``zn = z / (cos^2(beta_b) cos(beta))`` (ISO 6336-1 eq. for
  ``z_n``; ``z / cos^3(beta)`` is its approximation), ``sin(beta_b) = sin(beta) cos(alpha_n)``;
* theoretical single stiffness ``c'_th = 1 / q'`` with the flexibility polynomial
  ``q' = C1 + C2/zn1 + C3/zn2 + C4 x1 + C5 x1/zn1 + C6 x2 + C7 x2/zn2 + C8 x1^2 + C9 x2^2``
  [mm um / N] (:data:`C_COEFFICIENTS`);
* single stiffness ``c' = c'_th C_M C_R C_B cos(beta)`` with ``C_M = 0.8``, the gear-blank
  factor ``C_R = 1 + ln(b_s/b) / (5 exp(s_R / (5 mn)))`` (``b_s/b`` clamped to [0.2, 1.2],
  ``s_R/mn >= 1``; 1 for solid blanks) and the basic-rack factor
  ``C_B = [1 + 0.5 (1.2 - h_fP/mn)] [1 - 0.02 (20 deg - alpha_n)]``; for a line load
  ``K_A F_t / b`` below 100 N/mm, ``c'`` is scaled by ``(K_A F_t / b) / (100 N/mm)``;
* mesh stiffness ``c_gamma_alpha = c' (0.75 eps_alpha + 0.25)`` (ISO states it for
  ``eps_alpha >= 1.2``; below, it overestimates by up to about 10 %) and
  ``c_gamma_beta = 0.85 c_gamma_alpha``;
* transverse contact ratio from the involute geometry at the working centre distance
  (zero-backlash: ``inv(alpha_wt) = inv(alpha_t) + 2 tan(alpha_n) (x1 + x2) / (z1 + z2)``),
  tip diameters ``d_a = d + 2 mn (h_aP/mn + x)``:
  ``eps_alpha = (sqrt(r_a1^2 - r_b1^2) + sqrt(r_a2^2 - r_b2^2) - a_w sin(alpha_wt)) / p_bt``,
  ``p_bt = pi mn cos(alpha_t) / cos(beta)``; overlap ratio ``eps_beta = b sin(beta) / (pi mn)``.

ISO's stiffness acts along the line of action in the transverse plane (its dynamic factor
uses the torsional mesh stiffness ``c_gamma_alpha b r_b^2``).  The dynamic model's mesh acts
along the 3-D tooth normal, whose transverse component is ``cos(beta_b)``; the same
torsional stiffness needs ``k_normal = c_gamma_alpha b / cos^2(beta_b)`` (= ``k_mean`` for
spur gears).

Time variation (:func:`contact_harmonics`).  In a transverse slice the tooth pairs in
contact alternate between two (a fraction ``eps_alpha - 1`` of the mesh period, beginning at
``t = 0`` when a new pair enters at the start of the path of contact) and one.  ISO's
``0.75 eps_alpha + 0.25`` is the mean of a rectangular wave whose double-contact level is
1.75 times the single-contact level ``c'``; relative to the mean the wave is
``k(t) / k_mean = 1 + sum_h a_h cos(h W t) + b_h sin(h W t)`` with, for a pulse of height
``D = 0.75 / (0.75 eps_alpha + 0.25)`` over the fraction ``f = eps_alpha - 1``,
``a_h = D sin(2 pi h f) / (pi h)``, ``b_h = D (1 - cos(2 pi h f)) / (pi h)``.  Across the face
width of a helical gear the slices are shifted by up to ``eps_beta`` mesh periods; averaging
over the face multiplies harmonic h by ``sinc(h eps_beta) exp(-i pi h eps_beta)`` (the total
contact-line length is constant when ``eps_beta`` is an integer).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["C_COEFFICIENTS", "C_M", "N_PER_MM_UM", "MeshStiffness", "virtual_teeth",
           "theoretical_single_stiffness", "blank_factor", "basic_rack_factor", "involute",
           "inverse_involute", "contact_ratios", "contact_harmonics", "mesh_stiffness"]

#: C1..C9 of the flexibility polynomial q' [mm um / N] (ISO 6336-1:2006, Table 8)
C_COEFFICIENTS = (0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188,
                  0.00529, 0.00182)
#: theoretical correction factor C_M
C_M = 0.8
#: 1 N/(mm um) in N/m^2
N_PER_MM_UM = 1e9
#: 100 N/mm in N/m: the line load below which c' is scaled down
_LINE_LOAD_REF = 1e5


def _check(ok: bool, message: str) -> None:
    if not ok:
        raise ValueError(message)


def involute(alpha):
    """inv(alpha) = tan(alpha) - alpha."""
    return np.tan(alpha) - alpha


def inverse_involute(value: float) -> float:
    """alpha in (0, pi/2) with inv(alpha) = value: Newton safeguarded by bisection (inv is
    increasing on (0, pi/2))."""
    _check(value > 0.0, f"involute function value must be > 0, got {value}")
    lo, hi = 0.0, 0.5 * math.pi
    a = min((3.0 * value) ** (1.0 / 3.0), 0.5 * (lo + hi))
    for _ in range(200):
        t = math.tan(a)
        r = t - a - value
        if r > 0.0:
            hi = a
        else:
            lo = a
        nxt = a - r / (t * t)
        if not lo < nxt < hi:
            nxt = 0.5 * (lo + hi)
        if abs(nxt - a) <= 1e-15 * a:
            return nxt
        a = nxt
    return a


def virtual_teeth(z: float, beta: float, alpha_n: float) -> float:
    """z_n = z / (cos^2(beta_b) cos(beta)) with sin(beta_b) = sin(beta) cos(alpha_n)."""
    beta_b = math.asin(math.sin(beta) * math.cos(alpha_n))
    return z / (math.cos(beta_b) ** 2 * math.cos(beta))


def theoretical_single_stiffness(zn1: float, zn2: float, x1: float = 0.0,
                                 x2: float = 0.0) -> float:
    """c'_th = 1 / q' [N/m^2] (q' of the module docstring, evaluated in mm um / N)."""
    c1, c2, c3, c4, c5, c6, c7, c8, c9 = C_COEFFICIENTS
    q = (c1 + c2 / zn1 + c3 / zn2 + c4 * x1 + c5 * x1 / zn1 + c6 * x2 + c7 * x2 / zn2
         + c8 * x1 ** 2 + c9 * x2 ** 2)
    _check(q > 0.0, f"flexibility q' = {q:g} mm um/N is not positive (profile shifts "
           "outside the polynomial's range)")
    return N_PER_MM_UM / q


def blank_factor(web_ratio: float = 1.0, rim_ratio: float = 10.0) -> float:
    """C_R = 1 + ln(b_s/b) / (5 exp(s_R / (5 m_n))), b_s/b in [0.2, 1.2], s_R/m_n >= 1."""
    bs = min(max(web_ratio, 0.2), 1.2)
    sr = max(rim_ratio, 1.0)
    return 1.0 + math.log(bs) / (5.0 * math.exp(sr / 5.0))


def basic_rack_factor(dedendum: float = 1.25, alpha_n: float = math.radians(20.0)) -> float:
    """C_B = [1 + 0.5 (1.2 - h_fP/m_n)] [1 - 0.02 (20 deg - alpha_n)] (alpha_n in rad)."""
    return (1.0 + 0.5 * (1.2 - dedendum)) * (1.0 - 0.02 * (20.0 - math.degrees(alpha_n)))


def contact_ratios(z1: int, z2: int, mn: float, alpha_n: float, beta: float = 0.0,
                   x1: float = 0.0, x2: float = 0.0, addendum: float = 1.0,
                   face_width: float = 0.0, centre_distance: float | None = None):
    """(eps_alpha, eps_beta, alpha_wt, a_w): transverse and overlap contact ratios, working
    transverse pressure angle [rad] and working centre distance [m] (zero backlash from the
    profile shifts unless ``centre_distance`` is given)."""
    alpha_t = math.atan(math.tan(alpha_n) / math.cos(beta))
    d1, d2 = mn * z1 / math.cos(beta), mn * z2 / math.cos(beta)
    a = 0.5 * (d1 + d2)
    if centre_distance is None:
        inv_w = float(involute(alpha_t)) + 2.0 * math.tan(alpha_n) * (x1 + x2) / (z1 + z2)
        alpha_wt = inverse_involute(inv_w)
        a_w = a * math.cos(alpha_t) / math.cos(alpha_wt)
    else:
        a_w = float(centre_distance)
        _check(a * math.cos(alpha_t) < a_w, f"centre distance {a_w:g} m is too small")
        alpha_wt = math.acos(a * math.cos(alpha_t) / a_w)
    rb1, rb2 = 0.5 * d1 * math.cos(alpha_t), 0.5 * d2 * math.cos(alpha_t)
    ra1, ra2 = 0.5 * d1 + mn * (addendum + x1), 0.5 * d2 + mn * (addendum + x2)
    _check(ra1 > rb1 and ra2 > rb2, "tip circle inside the base circle")
    g_alpha = math.sqrt(ra1 ** 2 - rb1 ** 2) + math.sqrt(ra2 ** 2 - rb2 ** 2) \
        - a_w * math.sin(alpha_wt)
    p_bt = math.pi * mn * math.cos(alpha_t) / math.cos(beta)
    eps_beta = face_width * abs(math.sin(beta)) / (math.pi * mn)
    return g_alpha / p_bt, eps_beta, alpha_wt, a_w


def contact_harmonics(eps_alpha: float, eps_beta: float = 0.0, count: int = 3):
    """(a_h, b_h), h = 1..count: relative harmonics of k(t)/k_mean (module docstring)."""
    _check(1.0 <= eps_alpha <= 2.0, f"the single/double contact wave needs 1 <= eps_alpha "
           f"<= 2, got {eps_alpha:.4g}")
    f = eps_alpha - 1.0
    height = 0.75 / (0.75 * eps_alpha + 0.25)
    h = np.arange(1, count + 1, dtype=float)
    spur = height / (np.pi * h) * ((np.sin(2 * np.pi * h * f))
                                   + 1j * (1.0 - np.cos(2 * np.pi * h * f)))  # a + i b
    # face averaging: the slice at axial fraction s lags by s eps_beta periods
    smooth = np.sinc(h * eps_beta) * np.exp(1j * np.pi * h * eps_beta)
    z = spur * smooth
    return tuple(float(v) for v in z.real), tuple(float(v) for v in z.imag)


@dataclass(frozen=True)
class MeshStiffness:
    """ISO 6336-1 method B values of one gear pair (SI)."""
    zn1: float
    zn2: float
    c_th: float             # theoretical single stiffness c'_th [N/m^2]
    c_prime: float          # single stiffness c' [N/m^2]
    c_gamma_alpha: float    # mesh stiffness c_gamma_alpha [N/m^2]
    c_gamma_beta: float     # 0.85 c_gamma_alpha [N/m^2]
    C_R: float
    C_B: float
    load_factor: float      # low line-load scaling of c' (1 if not applied)
    eps_alpha: float
    eps_beta: float
    working_pressure_angle: float   # alpha_wt [rad]
    working_centre_distance: float  # a_w [m]
    base_helix_angle: float         # beta_b [rad]
    face_width: float               # b [m]
    harmonics_cos: tuple
    harmonics_sin: tuple

    @property
    def k_mean(self) -> float:
        """c_gamma_alpha b [N/m]: along the transverse line of action (ISO)."""
        return self.c_gamma_alpha * self.face_width

    @property
    def k_normal(self) -> float:
        """k_mean / cos^2(beta_b) [N/m]: the same mesh along the 3-D tooth normal."""
        return self.k_mean / math.cos(self.base_helix_angle) ** 2

    def as_dict(self) -> dict:
        return {"c_th_N_per_mm_um": self.c_th / N_PER_MM_UM,
                "c_prime_N_per_mm_um": self.c_prime / N_PER_MM_UM,
                "c_gamma_alpha_N_per_mm_um": self.c_gamma_alpha / N_PER_MM_UM,
                "eps_alpha": self.eps_alpha, "eps_beta": self.eps_beta,
                "k_mean_N_per_m": self.k_mean, "k_normal_N_per_m": self.k_normal,
                "zn": [self.zn1, self.zn2], "C_R": self.C_R, "C_B": self.C_B,
                "load_factor": self.load_factor,
                "harmonics_cos": list(self.harmonics_cos),
                "harmonics_sin": list(self.harmonics_sin)}


def mesh_stiffness(z1: int, z2: int, mn: float, face_width: float, *,
                   alpha_n: float = math.radians(20.0), beta: float = 0.0, x1: float = 0.0,
                   x2: float = 0.0, addendum: float = 1.0, dedendum: float = 1.25,
                   web_ratio: float = 1.0, rim_ratio: float = 10.0,
                   line_load: float | None = None, centre_distance: float | None = None,
                   harmonics: int = 3) -> MeshStiffness:
    """ISO 6336-1:2006 method B for an external pair (angles in rad, lengths in m,
    ``line_load`` = K_A F_t / b in N/m); raises ValueError outside the method's range."""
    _check(z1 >= 5 and z2 >= 5, f"teeth must be >= 5, got {z1}, {z2}")
    _check(mn > 0.0 and face_width > 0.0, "module and face width must be > 0")
    _check(0.0 < alpha_n < 0.5 * math.pi and abs(beta) < 0.5 * math.pi, "angles out of range")
    zn1, zn2 = virtual_teeth(z1, beta, alpha_n), virtual_teeth(z2, beta, alpha_n)
    c_th = theoretical_single_stiffness(zn1, zn2, x1, x2)
    c_r, c_b = blank_factor(web_ratio, rim_ratio), basic_rack_factor(dedendum, alpha_n)
    load = 1.0 if line_load is None else min(line_load / _LINE_LOAD_REF, 1.0)
    c_prime = c_th * C_M * c_r * c_b * math.cos(beta) * load
    eps_a, eps_b, alpha_wt, a_w = contact_ratios(z1, z2, mn, alpha_n, beta, x1, x2, addendum,
                                                 face_width, centre_distance)
    _check(eps_a > 1.0, f"transverse contact ratio eps_alpha = {eps_a:.4g} must be > 1")
    c_gamma = c_prime * (0.75 * eps_a + 0.25)
    if harmonics and eps_a <= 2.0:
        hc, hs = contact_harmonics(eps_a, eps_b, harmonics)
    else:
        hc, hs = (), ()
    return MeshStiffness(zn1=zn1, zn2=zn2, c_th=c_th, c_prime=c_prime, c_gamma_alpha=c_gamma,
                         c_gamma_beta=0.85 * c_gamma, C_R=c_r, C_B=c_b, load_factor=load,
                         eps_alpha=eps_a, eps_beta=eps_b, working_pressure_angle=alpha_wt,
                         working_centre_distance=a_w,
                         base_helix_angle=math.asin(abs(math.sin(beta)) * math.cos(alpha_n)),
                         face_width=face_width, harmonics_cos=hc, harmonics_sin=hs)
