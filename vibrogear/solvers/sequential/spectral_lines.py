"""Spectral lines: the peaks of a one-sided amplitude spectrum and the source of each (numpy).

A **line** is a local maximum of the amplitude spectrum (bins 1 .. K-1, the mean left out) at
or above ``threshold`` times the largest amplitude of the spectrum, at most ``max_lines`` of
them (the strongest).  The spectra of :mod:`.spectrum` have no window (rectangular), so a
tone of amplitude A at frequency (k + d) df, |d| <= 1/2, has |A_k| = A |sinc d| and
|A_{k+1}| / |A_k| = |d| / (1 - |d|); :func:`find_lines` inverts this: d from the larger
neighbour, the frequency (k + d) df and the amplitude |A_k| / sinc d.  A tone on a bin (a
harmonic of the record's period) has d = 0 and is exact.

A **source** (:class:`Source`) is a fundamental frequency with a name, a kind and the orders
h = 1 .. ``max_order`` it may appear at (a mesh's tooth-pass frequency and its harmonics, a
shaft's rotation, a bearing's cage / ball-pass frequency, a natural frequency).
:func:`identify` names each line:

1. the source order h f_s nearest to the line within ``tol`` (kinds in the order of
   :data:`KIND_RANK`, then the lowest order, then the nearest); other sources within ``tol``
   are listed as alternatives, never chosen over the first.  ``base`` frequencies (a torus's
   second frequency) are sources of kind "base" with orders 1 .. :data:`BASE_ORDERS` (the
   line that defines one is named by it whatever the chance test says);
2. else a combination tone a f_i + b f_j (1 <= |a|, |b| <= ``combo_max``, the fewest orders
   first) of two *parents*: the meshes that named a line in step 1 (at their exact
   tooth-pass frequency), the excitation ``f1``, the ``base`` frequencies and the
   :data:`MAX_PARENTS` strongest other lines named at order 1 in step 1 (a natural
   frequency, a bearing's or a free gear's line at the line's measured frequency, as a
   nonlinear system vibrates near, not at, them);
3. else ``"unidentified"``: a line is never forced onto the nearest candidate.

**Chance test**: a match in step 1 or 2 is a claim only where candidates are sparse: the
fraction of the neighbourhood +-32 tol of the line that lies within ``tol`` of a candidate of
that step (``chance``: the probability that a line at a random frequency there would match
something) must be at most :data:`CHANCE_MAX`.  Where it is larger (a coarse record, dense
shaft orders and modes), the line stays "unidentified" and its candidates are listed as
alternatives: the resolution cannot tell them apart.

**Base pair** of a torus (:func:`base_pair`): f1 is the excitation; each of the strongest
lines that is no harmonic of f1 is tried as f2, and the f2 whose lattice a f1 + b f2 (|b| <=
:data:`BASE_ORDERS`) explains the most line power is kept.  The pair is defined up to f2 -> +-f2 +
k f1 (the same lattice); the measured line is the representative given, and ``nu`` = the
fractional part of f2 / f1 folded into [0, 1/2] the canonical one.

**Broadband measures** (:func:`broadband_fraction`, :func:`spectral_flatness`): the fraction
of the signal's AC power in bins farther than ``halfwidth`` bins from every identified line
(leakage of an off-bin tone leaves < 5 % outside 3 bins), and the spectral flatness
geometric mean / arithmetic mean of the AC power bins (a line spectrum -> 0, white noise ->
exp(-gamma) = 0.56 for a periodogram).

**Stroboscopic evidence** (:func:`stroboscopic_evidence`): from the once-per-period samples of
a sweep point (no dense record needed), the rotation number nu in [0, 1/2] (the strongest
frequency of the Hann-windowed, 64x zero-padded sequence in cycles per period: a torus's
second base frequency folded onto the excitation) and the flatness of its spectrum.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Source", "Lines", "KIND_RANK", "UNIDENTIFIED", "THRESHOLD", "MAX_LINES",
           "COMBO_MAX", "MAX_PARENTS", "BASE_ORDERS", "CHANCE_MAX", "find_lines", "identify", "base_pair", "broadband_fraction",
           "spectral_flatness", "stroboscopic_evidence", "bearing_frequencies",
           "coverage"]

#: lines: local maxima at or above this fraction of the strongest amplitude (-40 dB)
THRESHOLD = 1e-2
#: at most this many lines per spectrum (the strongest)
MAX_LINES = 40
#: combination tones a f1 + b f2 with 1 <= |a|, |b| <= COMBO_MAX
COMBO_MAX = 3
#: combination tones: at most this many named non-mesh lines (the strongest) are parents
MAX_PARENTS = 1
#: a torus's base frequency f2 is tried at orders 1 .. BASE_ORDERS (rattle: impulsive)
BASE_ORDERS = 12
#: a match is a claim only where a random frequency near the line would match with a
#: chance of at most this (the fraction of +-32 tolerances around it within the
#: tolerance of a candidate)
CHANCE_MAX = 0.2
UNIDENTIFIED = "unidentified"
#: source kinds in the order a line is given to them
KIND_RANK = ("mesh", "shaft", "free gear", "bearing", "mode", "base")


@dataclass(frozen=True)
class Source:
    """A fundamental frequency ``freq`` that may appear at orders 1 .. ``max_order``;
    ``tol``: its own matching tolerance (None: the spectrum's)."""
    name: str
    freq: float
    kind: str
    max_order: int = 1
    tol: float | None = None

    def label(self, h: int) -> str:
        return self.name if self.max_order == 1 else f"{self.name} {h}x"


@dataclass(frozen=True, eq=False)
class Lines:
    """The lines of one spectrum (ascending frequency) with their sources."""
    freq: np.ndarray          # (L,) estimated frequency
    amp: np.ndarray           # (L,) amplitude (leakage corrected)
    bin: np.ndarray           # (L,) peak bin
    source: tuple = ()        # (L,) label, "unidentified" where nothing matched
    kind: tuple = ()          # (L,) a KIND_RANK kind, "combination" or "unidentified"
    offset: np.ndarray | None = None   # (L,) line minus matched frequency (NaN: none)
    alternatives: tuple = ()  # (L,) other sources within the tolerance, "; "-joined
    chance: np.ndarray | None = None   # (L,) chance of a match near the line (NaN: none)

    @property
    def identified(self) -> np.ndarray:
        return np.array([k != UNIDENTIFIED for k in self.kind], dtype=bool)

    def power_fraction(self, mask) -> float:
        """Fraction of the lines' power (amp^2) in the lines of ``mask``."""
        p = self.amp ** 2
        return float(p[np.asarray(mask, bool)].sum() / p.sum()) if p.sum() > 0 else 0.0


def find_lines(freq, amp, *, threshold: float = THRESHOLD, max_lines: int = MAX_LINES
               ) -> Lines:
    """The lines (module docstring) of the amplitude spectrum ``amp`` (K,) on the equidistant
    bins ``freq`` (K,), unnamed."""
    f = np.asarray(freq, dtype=float)
    a = np.asarray(amp, dtype=float)
    K = a.size
    empty = Lines(np.zeros(0), np.zeros(0), np.zeros(0, int))
    if K < 3 or not np.any(a[1:] > 0):
        return empty
    df = f[1] - f[0]
    ref = float(np.max(a[1:]))
    left = a[:-2]
    mid = a[1:-1]
    right = a[2:]
    k = np.flatnonzero((mid > left) & (mid >= right) & (mid >= threshold * ref)) + 1
    if a[-1] > a[-2] and a[-1] >= threshold * ref:
        k = np.append(k, K - 1)
    k = k[np.argsort(a[k])[::-1][:int(max_lines)]]
    k = np.sort(k)
    fr, am = np.empty(k.size), np.empty(k.size)
    for i, b in enumerate(k):
        lo = a[b - 1] if b - 1 >= 1 else 0.0
        hi = a[b + 1] if b + 1 < K else 0.0
        s, r = (1.0, hi / a[b]) if hi >= lo else (-1.0, lo / a[b])
        d = min(r / (1.0 + r), 0.5)
        fr[i] = f[b] + s * d * df
        am[i] = a[b] / _sinc(d)
    return Lines(fr, am, k)


def _sinc(d: float) -> float:
    return 1.0 if d == 0 else math.sin(math.pi * d) / (math.pi * d)


def _rank(kind: str) -> int:
    return KIND_RANK.index(kind) if kind in KIND_RANK else len(KIND_RANK)


def _chance(f: float, cand: np.ndarray, tol: float, window: float) -> float:
    """Fraction of [f - window, f + window] (clipped at 0) within ``tol`` of a candidate."""
    lo, hi = max(0.0, f - window), f + window
    c = np.sort(cand[(cand >= lo - tol) & (cand <= hi + tol)])
    if c.size == 0 or hi <= lo:
        return 0.0
    covered, end = 0.0, lo
    for x in c:
        a, b = max(x - tol, end), min(x + tol, hi)
        if b > a:
            covered += b - a
            end = b
    return covered / (hi - lo)


def identify(lines: Lines, sources, tol: float, *, f1: float | None = None, base=(),
             combo_max: int = COMBO_MAX, window: float | None = None,
             chance_max: float = CHANCE_MAX) -> Lines:
    """``lines`` with their sources (module docstring).  ``sources``: :class:`Source`;
    ``tol``: the matching tolerance (e.g. half a bin); ``f1``: the excitation frequency, a
    parent of combination tones; ``base``: [(name, frequency)] of a torus's other base
    frequencies, named with their orders up to :data:`BASE_ORDERS`.  ``window``: the
    half-width of the neighbourhood of the chance test (default 32 tolerances)."""
    f = lines.freq
    n = f.size
    W = 32.0 * tol if window is None else float(window)
    src = list(sources) + [Source(name, float(fb), "base", BASE_ORDERS) for name, fb in base
                           if np.isfinite(fb) and fb > 0]
    single = np.array([h * s.freq for s in src if s.freq > 0
                       for h in range(1, s.max_order + 1)])
    source, kind = [UNIDENTIFIED] * n, [UNIDENTIFIED] * n
    offset, alts, chance = np.full(n, np.nan), [""] * n, np.full(n, np.nan)
    strong: list = []                   # (power, name, frequency) of non-mesh parents
    mesh: dict[str, float] = {}
    for i in range(n):
        cands = []
        for s in src:
            if not s.freq > 0:
                continue
            h = int(round(f[i] / s.freq))
            t = tol if s.tol is None else max(tol, s.tol)
            for hh in {h, h - 1, h + 1}:
                if 1 <= hh <= s.max_order and abs(f[i] - hh * s.freq) <= t:
                    cands.append((_rank(s.kind), hh, abs(f[i] - hh * s.freq), s, hh))
        if not cands:
            continue
        chance[i] = _chance(f[i], single, tol, W)
        cands.sort(key=lambda c: c[:3])
        alts[i] = "; ".join(c[3].label(c[4]) for c in cands)
        own = [c for c in cands if c[3].kind == "base" and c[4] == 1]
        if own:                                # the line that defines a base frequency
            cands = own
        elif chance[i] > chance_max:
            continue                           # too many candidates here: not a claim
        _, _, _, s, h = cands[0]
        source[i], kind[i], offset[i] = s.label(h), s.kind, f[i] - h * s.freq
        alts[i] = "; ".join(c[3].label(c[4]) for c in cands[1:])
        if s.kind == "mesh":
            mesh.setdefault(s.name, s.freq)
        elif h == 1 and s.kind != "base":      # it vibrates at the line, near f_s
            strong.append((float(lines.amp[i]) ** 2, s.name, float(f[i])))
    parents = {k: (v, combo_max) for k, v in mesh.items()}
    if f1 is not None and f1 > 0 and not any(abs(v - f1) <= tol for v, _ in parents.values()):
        parents["f1"] = (float(f1), combo_max)
    parents.update({name: (float(fb), BASE_ORDERS) for name, fb in base
                    if np.isfinite(fb) and fb > 0})
    for _, name, fr in sorted(strong, reverse=True)[:MAX_PARENTS]:
        parents.setdefault(name, (fr, combo_max))
    items = list(parents.items())
    combos = []                                # (frequency, |a| + |b|, label)
    for p in range(len(items)):
        for q in range(p + 1, len(items)):
            (n1, (fa, ma)), (n2, (fb, mb)) = items[p], items[q]
            for a in range(-ma, ma + 1):
                for b in range(-mb, mb + 1):
                    if a and b and a * fa + b * fb > 0:
                        combos.append((a * fa + b * fb, abs(a) + abs(b), a, n1, b, n2))
    cf = np.array([c[0] for c in combos])
    for i in range(n):
        if kind[i] != UNIDENTIFIED or cf.size == 0:
            continue
        hit = np.flatnonzero(np.abs(f[i] - cf) <= tol)
        if hit.size == 0:
            continue
        chance[i] = _chance(f[i], cf, tol, W)
        best = min(hit, key=lambda j: (combos[j][1], abs(f[i] - cf[j])))
        c = combos[best]
        if chance[i] > chance_max:
            alts[i] = "; ".join(filter(None, [alts[i], _combo(*c[2:])]))
            continue
        source[i], kind[i], offset[i] = _combo(*c[2:]), "combination", f[i] - c[0]
    return Lines(lines.freq, lines.amp, lines.bin, tuple(source), tuple(kind), offset,
                 tuple(alts), chance)


def _combo(a: int, n1: str, b: int, n2: str) -> str:
    first = f"{a}x {n1}" if a > 0 else f"-{-a}x {n1}"
    return f"{first} {'+' if b > 0 else '-'} {abs(b)}x {n2}"


def base_pair(lines: Lines, f1: float, tol: float, *, candidates: int = 5,
              orders: int = BASE_ORDERS) -> dict:
    """The torus base pair (module docstring) of ``lines`` with excitation ``f1``:
    {"f1", "f2" (NaN: no line off the harmonics of f1), "nu", "explained" (fraction of the
    line power on the lattice a f1 + b f2), "harmonic" (the fraction on harmonics of f1
    alone), "rational" (the nearest p/q, q <= 8, to nu and its distance in cycles)}."""
    f, p = lines.freq, lines.amp ** 2
    total = float(p.sum())
    out = {"f1": float(f1), "f2": math.nan, "nu": math.nan, "explained": 0.0,
           "harmonic": 0.0, "rational": (0, 1, math.nan)}
    if total <= 0 or not f1 > 0:
        return out
    on_h = np.abs(f - np.round(f / f1) * f1) <= tol
    out["harmonic"] = out["explained"] = float(p[on_h].sum() / total)
    off = np.flatnonzero(~on_h)
    off = off[np.argsort(p[off])[::-1][:candidates]]
    best = None
    for i in off:
        f2 = f[i]
        b = np.arange(-orders, orders + 1)
        # nearest lattice point a f1 + b f2 for each b
        r = f[:, None] - b[None, :] * f2
        on = np.any(np.abs(r - np.round(r / f1) * f1) <= tol, axis=1)
        e = float(p[on].sum() / total)
        if best is None or e > best[0] + 1e-12:
            best = (e, f2)
    if best is not None:
        out["explained"], out["f2"] = best
        nu = (best[1] / f1) % 1.0
        out["nu"] = min(nu, 1.0 - nu)
        out["rational"] = _nearest_rational(out["nu"])
    return out


def _nearest_rational(x: float, qmax: int = 8) -> tuple[int, int, float]:
    best = (0, 1, abs(x))
    for q in range(1, qmax + 1):
        pn = round(x * q)
        if abs(x - pn / q) < best[2] - 1e-15:
            best = (int(pn), q, abs(x - pn / q))
    return best


def broadband_fraction(amp, n_samples: int, bins, *, halfwidth: int = 3) -> float:
    """Fraction of the AC power of the one-sided amplitudes ``amp`` (K,) of ``n_samples``
    samples in bins farther than ``halfwidth`` from every bin in ``bins`` (the identified
    lines)."""
    a = np.asarray(amp, dtype=float)
    w = np.full(a.size, 0.5)
    w[0] = 0.0
    if n_samples % 2 == 0:
        w[-1] = 1.0
    pw = w * a ** 2
    total = float(pw.sum())
    if total <= 0:
        return 0.0
    near = np.zeros(a.size, bool)
    for b in np.asarray(bins, dtype=int).ravel():
        near[max(0, b - halfwidth):b + halfwidth + 1] = True
    return float(pw[~near].sum() / total)


def spectral_flatness(amp, *, floor: float = 1e-30, bins: int | None = None) -> float:
    """Geometric over arithmetic mean of the power amp^2 of the AC bins 1 .. K-1 (the
    Nyquist bin left out; ``bins``: only 1 .. bins - 1, the band the signal lives in): 0
    for lines, ~0.56 for white noise."""
    p = np.asarray(amp, dtype=float)[1:-1 if bins is None else int(bins)] ** 2
    if p.size == 0 or not np.any(p > 0):
        return 0.0
    p = np.maximum(p, floor * p.max())
    return float(np.exp(np.mean(np.log(p))) / np.mean(p))


def stroboscopic_evidence(samples, *, pad: int = 64, rel_still: float = 1e-9) -> dict:
    """{"nu", "flatness", "peak_fraction"} of once-per-period samples (R,) (module
    docstring): nu in [0, 1/2] cycles per period (0 for samples that do not move: a
    period-1 point), the flatness of the Hann-windowed spectrum, and the fraction of its
    power within the main lobe (+-2 bins) of nu and of its folded harmonics 2 nu, 3 nu."""
    x = np.asarray(samples, dtype=float).ravel()
    x = x[np.isfinite(x)]
    out = {"nu": 0.0, "flatness": 0.0, "peak_fraction": 1.0}
    if x.size < 8:
        return {k: math.nan for k in out}
    x = x - x.mean()
    if not np.max(np.abs(x)) > rel_still * max(1e-300, float(np.max(np.abs(samples)))):
        return out
    R = x.size
    w = np.hanning(R + 2)[1:-1]
    X = np.abs(np.fft.rfft(x * w, n=pad * R))
    nu_grid = np.arange(X.size) / (pad * R)
    k = int(np.argmax(X[1:])) + 1
    out["nu"] = float(nu_grid[k])
    coarse = np.abs(np.fft.rfft(x * w)) ** 2
    out["flatness"] = spectral_flatness(np.sqrt(coarse))
    near = np.zeros(coarse.size, bool)
    for h in (1, 2, 3):
        fh = (h * out["nu"]) % 1.0
        fh = min(fh, 1.0 - fh) * R
        near[max(0, int(round(fh)) - 2):int(round(fh)) + 3] = True
    near[0] = False
    tot = float(coarse[1:].sum())
    out["peak_fraction"] = float(coarse[near].sum() / tot) if tot > 0 else 1.0
    return out


def bearing_frequencies(f_rot: float, elements: int, d_over_D: float,
                        contact_angle_deg: float = 0.0) -> dict:
    """Rolling-element bearing frequencies, inner race turning at ``f_rot``, outer race fixed
    (standard closed forms; ``d_over_D``: ball over pitch diameter): cage FTF = f/2 (1 - r
    cos a), BPFO = n FTF, BPFI = n f/2 (1 + r cos a), BSF = f / (2 r) (1 - (r cos a)^2)."""
    r = float(d_over_D) * math.cos(math.radians(contact_angle_deg))
    ftf = 0.5 * f_rot * (1.0 - r)
    return {"FTF": ftf, "BPFO": elements * ftf, "BPFI": 0.5 * elements * f_rot * (1.0 + r),
            "BSF": f_rot / (2.0 * d_over_D) * (1.0 - r ** 2)}


def coverage(sources, tol: float, f_max: float) -> dict:
    """Per kind, the fraction of [0, f_max] within ``tol`` (or the source's own) of one of
    its orders: the chance that a line at a random frequency matches that kind."""
    out: dict = {}
    grid = np.linspace(0.0, f_max, 20001)
    for kind in {s.kind for s in sources}:
        hit = np.zeros(grid.size, bool)
        for s in sources:
            if s.kind != kind or not s.freq > 0:
                continue
            t = tol if s.tol is None else max(tol, s.tol)
            for h in range(1, min(s.max_order, int(f_max / s.freq) + 1) + 1):
                hit |= np.abs(grid - h * s.freq) <= t
        out[kind] = float(hit.mean())
    return out
