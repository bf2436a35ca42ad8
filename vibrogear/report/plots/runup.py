"""Figures of a run-up / run-down: envelopes over the steady state, order tracks, waterfall."""
from __future__ import annotations

import numpy as np

from ..figure import new_figure, plain_title

__all__ = ["plot_envelopes", "plot_orders", "plot_waterfall"]

_RUN_STYLE = {"up": dict(color="tab:blue", label="run-up"),
              "down": dict(color="tab:red", label="run-down")}
#: the run without the inertia torque next to the main one (inertia_torque = "both")
_NO_INERTIA = {"up": dict(color="tab:cyan", label="run-up, no inertia torque"),
               "down": dict(color="tab:orange", label="run-down, no inertia torque")}


def _style(r) -> dict:
    if getattr(r, "main", True):
        return {**_RUN_STYLE.get(r.direction, {}), "zorder": 2}
    return {**_NO_INERTIA.get(r.direction, {}), "ls": "--", "zorder": 1}


def _main_runs(result) -> list:
    return [r for r in result.runs if getattr(r, "main", True)]


def _steady(ax, sweep, branch, unit_label):
    if sweep is not None:
        for d, marker in (("up", "^"), ("down", "v")):
            sel = np.asarray(sweep["direction"]) == d
            for k, q in enumerate(("qmax", "qmin")):
                ax.plot(sweep["param"][sel], sweep[q][sel], marker, ms=3, color="0.25",
                        ls="none", label=f"sweep {d}" if k == 0 else None, zorder=3)
    if branch is not None and np.size(branch["param"]):
        ids = np.asarray(branch.get("branch", np.zeros(np.size(branch["param"]), int)))
        first = True
        for b in np.unique(ids):
            sel = ids == b
            p, st = np.asarray(branch["param"])[sel], np.asarray(branch["stable"])[sel]
            for q in ("qmax", "qmin"):
                v = np.asarray(branch[q])[sel]
                for stable, ls in ((True, "-"), (False, "--")):
                    y = np.where(st == stable, v, np.nan)
                    lab = None
                    if first and q == "qmax":
                        lab = "branch (stable)" if stable else "branch (unstable)"
                    ax.plot(p, y, ls, color="k", lw=1.2, label=lab, zorder=4)
            first = False


def plot_envelopes(result, *, sweep=None, branch=None):
    """Per mesh: the envelope (min and max per mesh period) against the speed for each
    run (with inertia_torque = "both" the runs without the inertia torque dashed); on the
    monitored mesh, the steady-state sweep and branches overlaid."""
    study = result.study
    n = len(result.mesh_names)
    fig = new_figure((9.0, 3.6 * n))
    mon_name = (study.model.contacts.names[study.model.monitor]
                if study.model.contacts.names else None)
    for i, name in enumerate(result.mesh_names):
        ax = fig.add_subplot(n, 1, i + 1)
        for r in result.runs:
            st = _style(r)
            kw = dict(lw=0.7, ls=st.get("ls", "-"), color=st.get("color"), zorder=st["zorder"])
            ax.plot(r.rpm, r.env_max[i], label=st.get("label"), **kw)
            ax.plot(r.rpm, r.env_min[i], **kw)
        if name == mon_name:
            _steady(ax, sweep, branch, study.monitor.unit)
            for r in _main_runs(result):
                if r.jump is not None:
                    st = _style(r)
                    ax.axvline(r.jump["rpm"], color=st.get("color"), lw=0.8, ls=":")
                    ax.annotate(f"{st.get('label', r.direction)} jump {r.jump['rpm']:.1f}",
                                (r.jump["rpm"], 1.0), xycoords=("data", "axes fraction"),
                                rotation=90, va="top", ha="right", fontsize=7,
                                color=st.get("color"))
        if study.monitor.zero_line:
            ax.axhline(0.0, color="0.6", lw=0.6)
        speeds = np.concatenate([r.rpm for r in result.runs])
        if speeds.size and np.ptp(speeds) > 0:
            lo, hi = speeds.min(), speeds.max()
            ax.set_xlim(lo - 0.03 * (hi - lo), hi + 0.03 * (hi - lo))
        ax.set_xlabel(study.param_label)
        ax.set_ylabel(f"{name} deformation [{study.monitor.unit}]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    rates = ", ".join(f"{r.direction}: {abs(np.ptp(r.rpm)) / max(np.ptp(r.time_s), 1e-30):.4g} "
                      f"{study.param_unit}/s" for r in _main_runs(result))
    both = len(_main_runs(result)) < len(result.runs)
    inertia = ("with and without (dashed) the inertia torque" if both else
               "with the inertia torque" if all(getattr(r, "inertia_torque", False)
                                                for r in result.runs)
               else "without the inertia torque")
    fig.axes[0].set_title(f"{plain_title(study.title)}\nenvelope per mesh period ({rates}; "
                          f"{inertia})", fontsize=9)
    return fig


def plot_orders(result):
    """Per mesh: amplitude of each tracked order against the speed (run-up solid,
    run-down dashed; the main runs, with the inertia torque where "both")."""
    study = result.study
    n = len(result.mesh_names)
    fig = new_figure((9.0, 3.6 * n))
    colors = [f"C{k % 10}" for k in range(len(result.order_names))]
    for i, name in enumerate(result.mesh_names):
        ax = fig.add_subplot(n, 1, i + 1)
        runs = _main_runs(result)
        for r in runs:
            ls = "-" if r.direction == "up" else "--"
            tr = r.tracks[name]
            for k, oname in enumerate(result.order_names):
                ax.semilogy(r.track_rpm, np.maximum(tr.amplitude[k], 1e-30), ls, lw=1.0,
                            color=colors[k],
                            label=f"{oname} ({result.orders[k]:.4g})" if r is runs[0]
                            else None)
        ax.set_xlabel(study.param_label)
        ax.set_ylabel(f"{name} order amplitude [{study.monitor.unit}]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, ncol=3, loc="best", title="order (per rev)", title_fontsize=7)
    fig.axes[0].set_title(f"{plain_title(study.title)}\norder tracks (window "
                          f"{result.runs[0].tracks[result.mesh_names[0]].window_revs} rev; "
                          "run-up solid, run-down dashed)", fontsize=9)
    return fig


def plot_waterfall(result):
    """Per direction: amplitude spectrum (dB) of the monitored mesh deformation against
    speed and frequency, with the order lines f = order x speed / 60 drawn."""
    study = result.study
    runs = _main_runs(result)
    fig = new_figure((9.0, 4.2 * len(runs)))
    for i, r in enumerate(runs):
        ax = fig.add_subplot(len(runs), 1, i + 1)
        wf = r.waterfall
        x = r.waterfall_rpm
        monotone = np.all(np.diff(x) > 0) or np.all(np.diff(x) < 0)
        xs = x if monotone else wf.time_s
        order = np.argsort(xs)
        A = wf.amplitude[:, order]
        db = 20 * np.log10(np.maximum(A, 1e-12 * max(A.max(), 1e-300)))
        top = db.max() if db.size else 0.0
        mesh = ax.pcolormesh(xs[order], wf.frequency_hz, db, shading="nearest",
                             vmin=top - 80, vmax=top, cmap="viridis", rasterized=True)
        fig.colorbar(mesh, ax=ax, label=f"dB re 1 {study.monitor.unit}")
        fmax = wf.frequency_hz[-1] if wf.frequency_hz.size else 1.0
        for k, (oname, o) in enumerate(zip(result.order_names, result.orders)):
            f = o * x[order] / 60.0
            if f.min() > fmax:
                continue
            ax.plot(xs[order], f, color="w", lw=0.6, ls=":" if "_1x" not in oname else "--")
            j = int(np.argmin(np.abs(np.minimum(f, fmax) - 0.95 * np.minimum(f, fmax).max())))
            if 0.05 * fmax <= f[j] <= fmax:
                ax.text(xs[order][j], f[j], oname.replace("_", " "), color="k", fontsize=7,
                        va="bottom", ha="right", bbox=dict(boxstyle="square,pad=0.1",
                                                           fc="white", ec="none", alpha=0.75))
        ax.set_ylim(0, fmax)
        ax.set_xlabel(study.param_label if monotone else "time [s]")
        ax.set_ylabel("frequency [Hz]")
        ax.set_title(f"{_RUN_STYLE.get(r.direction, {}).get('label', r.direction)}: "
                     f"{result.mesh_names[0] if len(result.mesh_names) == 1 else 'monitored mesh'}"
                     " deformation", fontsize=9)
    fig.axes[0].set_title(f"{plain_title(study.title)}\n" + fig.axes[0].get_title(), fontsize=9)
    return fig
