"""[findings]: the rules that turn a run's results into speed bands with a severity.

Every gearbox run ends with findings (``summary.json`` ``findings``, the console's last lines,
the top of ``report.html``).  A band is a run of neighbouring grid speeds at which one test
``metric op threshold`` holds on a per-point array of a written file (``sweep.npz``,
``map.npz``, ``erp.csv``); its severity is the rule's.  The defaults are written out in
``docs/findings.md``; change them here, for example ``quasi_periodic = "fine"`` where a
torus of small amplitude is acceptable, or ``back_impacts_above = 0.05`` to ignore rare
rattle impacts.

Each gear mesh is judged by its role in the static load path (``summary.json``
``load_path``): a *loaded* mesh by its dynamic factor and its contact loss, an *idle* mesh
(a free gear held only by its drag torque) by its rattle level.

Severities: ``avoid`` (do not operate there), ``caution`` (acceptable only with a reason:
look at the evidence) and ``fine`` (reported, not flagged).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

from ..base import spec

__all__ = ["FindingsConfig", "SEVERITIES", "PRIORITY", "base_quantity", "rank"]

#: from least to most severe
SEVERITIES = ("fine", "caution", "avoid")
#: the kinds of band, most telling first (the console and the verdict keep this order)
PRIORITY = ("contact loss", "rattle above the limit", "dynamic factor", "impacts in a state",
            "dynamic factor in a state",
            "rattle", "rattle in a state", "double-sided impacts", "ISO 6336 main resonance",
            "coexisting states",
            "chaotic motion", "subharmonic motion", "quasi-periodic motion",
            "motion not settled", "aperiodic motion", "hysteresis (up and down differ)",
            "bearing unloading", "radiated power", "quietest rattle")
_RUNS = (" in the run-up", " in the run-down")


def base_quantity(quantity: str) -> str:
    """The kind of a band, a run-up's or run-down's contact loss counted as contact loss."""
    for suffix in _RUNS:
        if quantity.endswith(suffix):
            return quantity[:-len(suffix)]
    return quantity


def rank(quantity: str) -> int:
    base = base_quantity(quantity)
    return PRIORITY.index(base) if base in PRIORITY else len(PRIORITY)


def _severity(default: str, what: str):
    return spec(default, choices=SEVERITIES, doc=f"severity of a band where {what}")


@dataclass(frozen=True, kw_only=True)
class FindingsConfig:
    """[findings]: thresholds and the severity of each kind of band."""
    loss_share_avoid: float = spec(0.01, ge=0.0, lt=1.0, doc="a loaded mesh loses contact "
                                   "where it is out of contact more than this share of the "
                                   "time (contact_fraction_<mesh> < 1 - loss_share_avoid)")
    contact_loss: str = _severity("avoid", "a loaded mesh loses contact")
    kv_caution: float = spec(1.3, gt=1.0, le=100.0, doc="the dynamic factor of a loaded "
                             "mesh (kv_<mesh>: largest mesh force / static mesh force) above "
                             "which a speed is flagged")
    dynamic_factor: str = _severity("caution", "a loaded mesh's dynamic factor exceeds "
                                    "kv_caution")
    iso_resonance: str = _severity("caution", "the speed lies in a loaded mesh's main "
                                   "resonance range by ISO 6336-1 (0.85 < N <= 1.15)")
    back_impacts_above: float = spec(0.0, ge=0.0, le=1e6, doc="a loaded mesh hits its back "
                                     "flank where impacts_back_<mesh> (back-flank impacts "
                                     "per mesh period) is above this")
    rattle: str = _severity("avoid", "a loaded mesh hits its back flank")
    double_sided: str = _severity("avoid", "a loaded mesh hits both flanks")
    rattle_caution_db: float = spec(6.0, gt=0.0, le=200.0, doc="an idle gear's rattle is "
                                    "flagged within this many dB of its loudest level over "
                                    "the run (rattle_db_<mesh>)")
    rattle_limit_db: float | None = spec(None, ge=-100.0, le=300.0, doc="rattle level [dB "
                                         "re 1 pW] above which an idle gear's speed is to be "
                                         "avoided (unset: no limit; no public absolute "
                                         "limit exists)")
    idle_rattle: str = _severity("caution", "an idle gear rattles within rattle_caution_db "
                                 "of its loudest")
    unloaded_above: float = spec(1.5, ge=0.0, le=1e4, doc="a bearing unloads where "
                                 "unloaded_<bearing> (mean rolling elements out of contact) "
                                 "exceeds its least value over the run by more than this")
    bearing_unloading: str = _severity("caution", "a bearing's rolling elements unload")
    chaotic: str = _severity("caution", "the motion is chaotic")
    quasi_periodic: str = _severity("caution", "the motion is quasi-periodic")
    subharmonic: str = _severity("caution", "the motion is periodic with period n >= 2")
    not_settled: str = _severity("caution", "the motion did not settle")
    jump_rel: float = spec(0.15, gt=0.0, le=1.0, doc="a jump: neighbouring sweep points whose "
                           "qmax differs by more than this fraction of its range")
    jump_level_rel: float = spec(0.05, ge=0.0, le=1.0, doc="... and by more than this "
                                 "fraction of the larger |qmax| of the two (a change of a few "
                                 "percent is a steep stretch of one response, not a jump)")
    hysteresis_rel: float = spec(0.05, gt=0.0, le=10.0, doc="up and down differ where "
                                 "|qmax_up - qmax_down| exceeds this fraction of the qmax "
                                 "range")
    hysteresis: str = _severity("caution", "the sweep up and down end in different states")
    erp_above_db: float | None = spec(None, ge=-400.0, le=400.0, doc="ERP level [dB re 1 "
                                      "pW] above which a speed is flagged (unset: 6 dB below "
                                      "the peak)")
    erp: str = _severity("caution", "the radiated power (ERP) is above erp_above_db")
    resonance_share_above: float = spec(0.05, ge=0.0, le=1.0, doc="a resonance speed is "
                                        "listed where the mode's mesh strain-energy share is "
                                        "above this")
    coexisting: str = _severity("caution", "another state coexists (from [states])")

    def rules(self) -> dict:
        """The rules as written into ``summary.json`` ``findings.rules``."""
        return asdict(self)
