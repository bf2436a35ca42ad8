"""[nnm]: nonlinear normal modes of a reduced model by continuation (``vibrogear nnm SCENE``).

The start mode is one linear mode of the conservative model linearised at the loaded static
state: ``mode`` (its index among the elastic modes, 0 = lowest), or the mode nearest
``frequency`` (Hz for a gearbox; for the impact pair its circular frequency in the unit of
Omega), or the mode with the largest strain-energy share of mesh ``mesh`` (gearbox); none
given: the impact pair's one mode, a gearbox's mesh mode of its monitored mesh.
``second_mode`` (an elastic-mode index) continues a second backbone.

The branch runs over the energy range [``energy_min``, ``energy_max``] above the static
state, in multiples of the start mode's contact-switch energy (``energy_unit = "onset"``:
the energy at which the linear mode first makes a contact switch, from the static state) or
absolute (``"absolute"``: J for a gearbox, model units for the impact pair); or, instead,
over the amplitude range [``amplitude_min``, ``amplitude_max``] of the monitored contact's
excursion max |delta - delta_s| (um for a gearbox, model units for the impact pair; the
start energy from the linear mode).  Steps ``ds``, ``ds_min``, ``ds_max`` are relative:
times the orbit's distance from the static state in state space.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..base import ConfigError, spec
from ..options import IntegrationOptions, NnmMethod, NnmSteps

__all__ = ["NnmConfig"]


@dataclass(frozen=True, kw_only=True)
class NnmConfig(NnmSteps):
    """[nnm]: start mode, energy or amplitude range, steps (:class:`NnmSteps`: ds, ds_min,
    ds_max, max_points, phase, stability_tol, rational_max, rational_tol), tolerances."""
    mode: int | None = spec(None, ge=0, le=100_000, doc="start mode: index among the "
                            "elastic modes (0 = lowest)")
    frequency: float | None = spec(None, gt=0.0, le=1e9, doc="start mode: the one nearest "
                                   "this frequency (Hz; impact pair: circular, unit of Omega)")
    mesh: str | None = spec(None, doc="start mode: the one with the largest strain-energy "
                            "share of this mesh (gearbox)")
    second_mode: int | None = spec(None, ge=0, le=100_000, doc="a second backbone from this "
                                   "elastic mode")
    energy_unit: str = spec("onset", choices=("onset", "absolute"), doc="energies in "
                            "multiples of the contact-switch energy, or absolute (J / model)")
    energy_min: float | None = spec(None, gt=0.0, le=1e30, doc="start energy above the "
                                    "static state")
    energy_max: float | None = spec(None, gt=0.0, le=1e30, doc="end energy")
    amplitude_min: float | None = spec(None, gt=0.0, le=1e30, doc="instead of energies: "
                                       "start excursion of the monitored contact (um / model)")
    amplitude_max: float | None = spec(None, gt=0.0, le=1e30, doc="end excursion")
    rtol: float = spec(1e-9, gt=0.0, lt=1e-3, doc="integrator rtol (atol = 1e-6 rtol for a "
                       "gearbox, 1e-2 rtol for the impact pair)")
    tol: float = spec(1e-7, gt=0.0, lt=1.0, doc="periodicity residual relative to the "
                      "orbit's size")
    shape_energies: tuple[float, ...] = spec((), max_len=20, gt=0.0, le=1e30,
                                             doc="energies (energy_unit) at which the orbit "
                                             "(mode shape over one period) is written")
    shape_samples: int = spec(64, ge=4, le=4096, doc="samples per period of a mode shape")

    def validate(self, path: str) -> None:
        given = [k for k in ("mode", "frequency", "mesh") if getattr(self, k) is not None]
        if len(given) > 1:
            raise ConfigError(f"{path}.{given[1]}", f"give one of mode, frequency, mesh "
                              f"(got {', '.join(given)})")
        amp = (self.amplitude_min is not None, self.amplitude_max is not None)
        en = (self.energy_min is not None, self.energy_max is not None)
        if any(amp) and any(en):
            raise ConfigError(f"{path}.amplitude_min", "give an energy range or an amplitude "
                              "range, not both")
        lo, hi, name = (("amplitude_min", "amplitude_max", "amplitude") if any(amp)
                        else ("energy_min", "energy_max", "energy"))
        a, b = getattr(self, lo), getattr(self, hi)
        if a is None or b is None:
            raise ConfigError(f"{path}.{lo if a is None else hi}", f"missing: the {name} "
                              f"range needs both {lo} and {hi} (numbers > 0)")
        if not a < b:
            raise ConfigError(f"{path}.{hi}", f"expected {hi} > {lo} = {a:g}, got {b:g}")

    def method(self, *, energy_min: float, energy_max: float, integration: IntegrationOptions,
               excursion_max: float | None = None, delta_static: float = 0.0) -> NnmMethod:
        """The solver's settings: this section's steps and tolerance over the energy range
        [energy_min, energy_max] in model units (known once the model is built)."""
        return NnmMethod(**self.steps(), tol=self.tol, energy_min=energy_min,
                         energy_max=energy_max, integration=integration,
                         excursion_max=excursion_max, delta_static=delta_static)

    def check_model(self, impact_pair, gearbox, path: str = "nnm") -> None:
        """The checks against the scene's model section that need no model build (the
        scene's validation runs them when it runs nnm, so ``vibrogear check`` reports them):

        * ``mesh`` names a mesh of [gearbox.meshes] (a gearbox option: the impact pair has
          none);
        * ``mode`` / ``second_mode`` within the elastic modes where their count is known from
          the config: the impact pair has one (index 0);
        * ``energy_unit = "onset"`` (an energy range) needs a static load on a gearbox whose
          every contact sits on its switch when unloaded (meshes: gap_hi = 0; bearings of
          clearance 0): without a load (every coupling's twist 0, no gravity, no free-gear
          drag torque) the static state is x = 0, on every contact's switch, so the
          contact-switch energy is 0 (inf for a mode that moves no contact) and cannot
          scale the range.

        What needs the model stays in :mod:`vibrogear.analyses.nnm`: a gearbox's number of
        elastic modes (master modes, static correction, housing, rigid-body modes: known
        after the reduction), and a zero or infinite contact-switch energy of a loaded model
        (a contact exactly at its gap in the loaded static state, a linear start mode)."""
        if self.mesh is not None:
            meshes = [m.name for m in gearbox.meshes] if gearbox is not None else []
            if self.mesh not in meshes:
                raise ConfigError(f"{path}.mesh", (f"expected the name of a mesh of "
                                  f"[gearbox.meshes] ({', '.join(meshes) or 'none'})"
                                  if gearbox is not None else "a gearbox option: this model "
                                  "has no mesh; give mode or frequency") +
                                  f", got {self.mesh!r}")
        if impact_pair is not None:
            for key in ("mode", "second_mode"):
                j = getattr(self, key)
                if j is not None and j != 0:
                    raise ConfigError(f"{path}.{key}", f"expected an elastic-mode index 0 .. 0 "
                                      f"(the impact pair has one mode), got {j}")
        if gearbox is not None and self.energy_unit == "onset" and self.amplitude_min is None:
            loaded = (any(c.static_twist for c in gearbox.couplings) or any(gearbox.gravity)
                      or any(g.free and g.drag_torque for g in gearbox.gears))
            # a contact bearing with a clearance is off its switch at x = 0: the analysis
            # decides from the model
            off_switch = any(b.type != "spring" and b.clearance > 0 for b in gearbox.bearings)
            if not loaded and not off_switch:
                raise ConfigError(f"{path}.energy_unit", "'onset': the gearbox has no static "
                                  "load (every coupling's twist is 0, no gravity, no drag "
                                  "torque), so its static state sits on the contact switch of "
                                  "every mesh (an unloaded mesh) and the contact-switch energy "
                                  "is 0: it cannot scale the range; give absolute energies "
                                  "(energy_unit = \"absolute\") or a static load")
