"""Plot of the critical-damping search: the two primary-resonance folds against zeta.

The lower and upper fold parameters of every continuation that found a fold pair are
plotted against zeta; they meet at the cusp.  The final bisection bracket is shaded and
the zetas without folds are marked on the axis.  Matplotlib ``Figure`` with the Agg
canvas: no pyplot state.
"""
from __future__ import annotations


import numpy as np

from ..figure import new_figure, plain_title

__all__ = ["plot_fold_cusp"]


def plot_fold_cusp(result, *, title: str = "", extra_scans=()):
    """The fold cusp as a Figure (the report writer saves it).  ``result``: a
    :class:`~vibrogear.analyses.critical_damping.CriticalDampingResult`; ``extra_scans``:
    more :class:`FoldScan` s (not part of the bisection) for the curves."""
    fig = new_figure((7.5, 4.8))
    ax = fig.add_subplot(111)
    with_f = sorted((s for s in [*result.scans, *extra_scans] if s.has_fold_pair),
                    key=lambda s: s.zeta)
    without = [s for s in result.scans if not s.has_fold_pair]
    z = np.array([s.zeta for s in with_f])
    lo = np.array([min(s.folds) for s in with_f])
    hi = np.array([max(s.folds) for s in with_f])
    if z.size:
        ax.plot(z, hi, "^-", color="tab:red", ms=5, label="upper fold (jump down)")
        ax.plot(z, lo, "v-", color="tab:blue", ms=5, label="lower fold (jump up)")
    zl, zh = result.bracket
    ax.axvspan(zl, zh, color="0.85", zorder=0)
    ax.axvline(result.zeta_critical, color="k", lw=1.0, ls="--",
               label=f"zeta_c = {result.zeta_critical:.5f} (bracket {zh - zl:.1e})")
    if np.isfinite(result.zeta_extrapolated):
        ax.axvline(result.zeta_extrapolated, color="tab:green", lw=1.0, ls=":",
                   label=f"gap^(2/3) extrapolation: {result.zeta_extrapolated:.5f}")
    if without:
        ylo = ax.get_ylim()[0] if z.size else 0.0
        ax.plot([s.zeta for s in without], [ylo] * len(without), "x", color="0.4",
                ls="none", clip_on=False, label="no folds")
    if z.size:
        ax.annotate(f"gap {hi[-1] - lo[-1]:.1e}\nat zeta {z[-1]:.5f}", (z[-1], 0.5 * (lo[-1] + hi[-1])),
                    textcoords="offset points", xytext=(-110, -30), fontsize=7,
                    arrowprops={"arrowstyle": "->", "color": "0.4", "lw": 0.8})
    ax.set_xlabel("zeta")
    ax.set_ylabel("fold parameter Omega (LP)")
    ax.set_title(plain_title(title) + f" ({result.continuations} continuations in the "
                 "bisection)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return fig
