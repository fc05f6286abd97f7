"""Design-chart data in HDF5: bifurcation curves (inside continuation files) and backbone files.

Bifurcation curves (``cablesim continue`` with ``continuation.loci``), beside the branches:

- ``/continuation/loci`` attributes ``parameter`` (the curves' second parameter: ``gamma``, or
  ``support`` for the support motion multiplier s), ``units`` (its unit: 1), ``<parameter>_start``,
  ``<parameter>_stop``, ``<parameter>_response`` (its value in the response curve whose
  bifurcations started them), ``complete``; in s also ``amplitude_<A|B>`` (m, each moving
  support's amplitude at s = 1) and ``amplitude_units`` (m);
- ``/continuation/loci/<name>/{omega, gamma, support, amplitude, halfrange, multipliers, state,
  trusted, special}`` (``kappa`` too on Neimark-Sacker curves; the parameter that is not the
  second constant), attributes ``kind``, ``period``, ``parameter``, ``channels``, ``end_first``,
  ``end_last``, ``origin_omega``, ``origin_<parameter>``, ``index``, ``plane`` (``out-of-plane``:
  a curve of a planar response's out-of-plane bifurcation);
- ``/continuation/codim2/{kind, omega, gamma, support, locus, amplitude, located}``: cusps,
  fold-flip points, strong resonances, generalized period doublings.

Backbone files (``cablesim backbone``): ``/backbone/{omega, amplitude, halfrange, multipliers,
ratios, stable, trusted, state, delta}`` with attributes ``mode``, ``linear_omega``, ``channels``,
``other_modes``, ``amplitude_max``, ``end``, ``complete``; ``/backbone/resonances/{kind, omega,
amplitude, mode, located}``; ``/modal/omega`` (the undamped linear frequencies).
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from ..errors import CablesimError
from .hdf5 import atomic_h5, attr_text, open_result, put, stamp

#: The curves' second parameters: (description in the files, unit).
SECOND = {"gamma": ("load factor gamma (scale of FL and of the supports' motion) along the curve", "1"),
          "support": ("support motion multiplier s along the curve: the supports move by gamma s times the "
                      "amplitudes of supports:", "1")}


def _strings(values) -> np.ndarray:
    return np.array([str(v) for v in values], dtype="S")


def _amplitudes(obj, amplitudes: dict) -> None:
    """Attributes ``amplitude_<A|B>`` (m): what the support multiplier s = 1 stands for."""
    for support, u in amplitudes.items():
        obj.attrs[f"amplitude_{support}"] = np.asarray(u, dtype=float)
    if amplitudes:
        obj.attrs["amplitude_units"] = "m"


def write_loci(g: h5py.Group, res) -> None:
    """The curves and codimension-two points of a
    :class:`~cablesim.analyses.continuation.ContinuationResult` into its ``/continuation`` group."""
    lg = g.create_group("loci")
    lo, hi = res.loci_range
    name = res.loci_parameter
    at = res.fixed_support if name == "support" else res.fixed
    lg.attrs.update({"parameter": name, "units": SECOND[name][1], f"{name}_start": lo, f"{name}_stop": hi,
                     f"{name}_response": at, "complete": bool(res.complete)})
    amplitudes = dict(getattr(res, "support_amplitudes", {}) or {})
    if name == "support":
        _amplitudes(lg, amplitudes)
    chans = _strings(res.channels)
    for k, L in enumerate(res.loci):
        h = lg.create_group(L.name)
        h.attrs.update({"kind": L.kind, "period": L.period, "end_first": L.ends[0], "end_last": L.ends[1],
                        "origin_omega": L.origin[0], f"origin_{name}": L.origin[1], "index": k, "plane": L.plane,
                        "parameter": name})
        h.attrs["channels"] = chans
        put(h, "omega", L.omega, "rad/s", "forcing frequency along the curve")
        for key in ("gamma", "support"):
            values = getattr(L, key)
            ds = put(h, key, values if values is not None else np.ones(L.omega.size), SECOND[key][1],
                     SECOND[key][0] + ("" if key == name else " (constant: the response's)"))
            if key == "support":
                _amplitudes(ds, amplitudes)
        if L.kappa is not None:
            put(h, "kappa", L.kappa, "1", "cos of the angle of the critical multipliers")
        put(h, "amplitude", L.amplitude, "m", "largest |z| over the bifurcating orbit, per channel")
        put(h, "halfrange", L.halfrange, "m", "half the peak-to-peak range over the orbit, per channel")
        put(h, "multipliers", L.multipliers, "1", "Floquet multipliers, by decreasing modulus")
        put(h, "state", L.state, "m, m/s", "(z, y') at forcing phase 0")
        put(h, "trusted", L.trusted, "1", "multipliers passed the residual and Liouville checks")
        put(h, "special", _strings(L.special), "1", "codimension-two point, turning point, level or bound")
    cg = g.create_group("codim2")
    pts = res.codim2
    put(cg, "kind", _strings(p.kind for p in pts), "1", "cusp, fold-flip, 1:1 ... 1:4 resonance, ...")
    put(cg, "omega", np.array([p.omega for p in pts], dtype=float), "rad/s", "forcing frequency")
    put(cg, "gamma", np.array([p.gamma for p in pts], dtype=float), "1", "load factor")
    put(cg, "support", np.array([p.support for p in pts], dtype=float), "1", "support motion multiplier s")
    put(cg, "locus", np.array([p.locus for p in pts], dtype=int), "1", "index of the curve")
    put(cg, "amplitude", np.array([p.amplitude for p in pts], dtype=float).reshape(len(pts), len(res.channels)),
        "m", "largest |z| over the orbit, per channel")
    put(cg, "located", np.array([p.located for p in pts], dtype=bool), "1", "location converged")


def read_loci(g: h5py.Group) -> dict | None:
    """The curves of a continuation file's ``/continuation`` group (None without them):
    ``parameter`` (the second: ``gamma`` or ``support``), ``start``, ``stop``, ``response`` (its
    range and its value in the response), the same as ``<parameter>_start`` ..., ``complete``,
    ``loci`` (list of dicts in curve order; ``values2``: the second parameter along the curve)
    and ``codim2`` (dict of arrays)."""
    if "loci" not in g:
        return None
    lg = g["loci"]
    second = attr_text(lg.attrs.get("parameter", "gamma"))  # (files before the support curves: gamma)
    out = {f"{second}_{k}": lg.attrs[f"{second}_{k}"] for k in ("start", "stop", "response")}
    out.update(parameter=second, start=float(out[f"{second}_start"]), stop=float(out[f"{second}_stop"]),
               response=float(out[f"{second}_response"]), complete=bool(lg.attrs.get("complete", True)))
    loci = []
    for name, h in lg.items():
        d = {k: np.asarray(h[k][()]) for k in h}
        d["special"] = [attr_text(s) for s in d["special"]]
        d.setdefault("support", np.ones(d["omega"].size))
        d.update(name=name, kind=attr_text(h.attrs["kind"]), period=int(h.attrs["period"]),
                 ends=(attr_text(h.attrs["end_first"]), attr_text(h.attrs["end_last"])),
                 origin=(float(h.attrs["origin_omega"]), float(h.attrs[f"origin_{second}"])),
                 index=int(h.attrs["index"]), plane=attr_text(h.attrs.get("plane", "in-plane")), values2=d[second])
        loci.append(d)
    out["loci"] = sorted(loci, key=lambda d: d["index"])
    cg = g["codim2"]
    c2 = {k: np.asarray(cg[k][()]) for k in cg}
    c2["kind"] = [attr_text(k) for k in c2.get("kind", [])]
    c2.setdefault("support", np.ones(len(c2["kind"])))
    c2["values2"] = c2[second]
    out["codim2"] = c2
    return out


def has_loci(path: str | Path) -> bool:
    """Whether a continuation file holds bifurcation curves."""
    try:
        with h5py.File(path, "r") as f:
            return "continuation/loci" in f
    except OSError:
        return False


def write_backbone(path: str | Path, res) -> Path:
    """Write a :class:`~cablesim.analyses.charts.BackboneResult` atomically."""
    with atomic_h5(path) as f:
        stamp(f, res.case_text, "backbone", analysis=res.analysis)
        g = f.create_group("backbone")
        g.attrs.update(mode=res.mode, linear_omega=res.linear_omega, amplitude_max=res.amplitude_max, end=res.end,
                       complete=bool(res.complete), case_name=res.case_name,
                       components=int(getattr(res, "components", 2)))  # per node: 2 planar, 3 spatial
        g.attrs["channels"] = _strings(res.channels)
        g.attrs["other_modes"] = np.array(res.other_modes, dtype=int)
        for k, v in res.stats.items():
            g.attrs[f"cost_{k}"] = v
        put(g, "omega", res.omega, "rad/s", "frequency of the free periodic orbit")
        put(g, "amplitude", res.amplitude, "m", "largest |z| over the orbit, per channel")
        put(g, "halfrange", res.halfrange, "m", "half the peak-to-peak range over the orbit, per channel")
        put(g, "multipliers", res.multipliers, "1", "Floquet multipliers (two at +1: the family's own)")
        put(g, "ratios", res.ratios, "1", "frequency of each other mode about the orbit / the orbit's frequency")
        put(g, "stable", res.stable, "1", "no multiplier off the unit circle")
        put(g, "trusted", res.trusted, "1", "residual and Liouville checks passed")
        put(g, "state", res.state, "m, m/s", "(z, y') at t = 0 (a turning point of the largest displacement)")
        put(g, "delta", res.delta, "1/s", "artificial damping (zero on a periodic orbit: a check)")
        rg = g.create_group("resonances")
        rs = res.resonances
        put(rg, "kind", _strings(r["kind"] for r in rs), "1", "k:l internal resonance with mode j")
        put(rg, "omega", np.array([r["omega"] for r in rs], dtype=float), "rad/s", "frequency")
        put(rg, "amplitude", np.array([r["amplitude"] for r in rs], dtype=float).reshape(len(rs), len(res.channels)),
            "m", "largest |z| over the orbit, per channel")
        put(rg, "mode", np.array([r["mode"] for r in rs], dtype=int), "1", "the other mode")
        put(rg, "located", np.array([r["located"] for r in rs], dtype=bool), "1", "location converged")
        m = f.create_group("modal")
        put(m, "omega", res.modal_omega, "rad/s", "undamped linear modal frequencies about the equilibrium")
    return Path(path)


def read_backbone(path: str | Path) -> dict:
    """A backbone file as plain arrays: the datasets of ``/backbone``, its attributes, the
    ``resonances`` (dict of arrays) and ``modal`` (rad/s)."""
    path = Path(path)
    with open_result(path, "backbone", "backbone", "cablesim backbone") as f:
        g = f["backbone"]
        out = {k: np.asarray(g[k][()]) for k in g if isinstance(g[k], h5py.Dataset)}
        for k in ("mode", "linear_omega", "amplitude_max"):
            out[k] = g.attrs[k].item() if hasattr(g.attrs[k], "item") else g.attrs[k]
        out["end"] = attr_text(g.attrs["end"])
        out["complete"] = bool(g.attrs.get("complete", True))
        out["case_name"] = attr_text(g.attrs.get("case_name", path.stem))
        out["channels"] = [attr_text(c) for c in np.asarray(g.attrs["channels"]).ravel()]
        out["other_modes"] = [int(m) for m in np.asarray(g.attrs["other_modes"]).ravel()]
        out["components"] = int(g.attrs.get("components", 2))
        out["analysis"] = attr_text(f.attrs.get("analysis", "exact"))
        rg = g["resonances"]
        rs = {k: np.asarray(rg[k][()]) for k in rg}
        rs["kind"] = [attr_text(k) for k in rs.get("kind", [])]
        out["resonances"] = rs
        out["modal"] = np.asarray(f["modal/omega"][()], dtype=float)
    return out
