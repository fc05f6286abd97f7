"""Text summaries of design charts: bifurcation curves and backbones (what the commands print)."""

from __future__ import annotations

import numpy as np

from ..version import __version__
from .continuation import support_meaning


def _table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max([len(h)] + [len(r[i]) for r in rows]) for i, h in enumerate(header)]
    return "\n".join("  " + "  ".join(c.rjust(w) for c, w in zip(cells, widths)) for cells in [header] + rows)


#: The curves' second parameters in the summary: (name in the text, symbol in the tables).
SECOND_WORDS = {"gamma": ("gamma", "gamma"), "support": ("support motion multiplier s", "s")}


def loci_summary(res) -> str:
    """The bifurcation curves of a :class:`~cablesim.analyses.continuation.ContinuationResult`:
    each curve's kind, the range of the second parameter (gamma or the support motion multiplier
    s) and of omega it spans, how it ends, and the codimension-two points."""
    second = res.loci_parameter
    words, sym = SECOND_WORDS[second]
    lo, hi = res.loci_range
    at = res.fixed_support if second == "support" else res.fixed
    meaning = support_meaning(res.support_amplitudes) if second == "support" else ""
    where = f"{sym} = {at:g}" + (f", gamma = {res.fixed:g}" if second == "support" else "")
    lines = ["", f"Bifurcation curves in (omega, {sym}), {words} from {lo:g} to {hi:g}"
             + (f" ({meaning})" if meaning else "") + f", started from the response at {where}:" if res.loci else
             f"No bifurcation curves: the response at {where} has no fold, period doubling or "
             "Neimark-Sacker point in the range."]
    if res.loci:
        rows = []
        for L in res.loci:
            y = L.values2
            k = int(np.argmin(y))
            rows.append([L.name, L.kind, str(L.period), f"{y.min():.4g} - {y.max():.4g}",
                         f"{L.omega.min():.5g} - {L.omega.max():.5g}", f"{y[k]:.5g} at {L.omega[k]:.5g} rad/s",
                         str(L.omega.size), f"{L.ends[0]}; {L.ends[1]}"])
        lines.append(_table(["curve", "kind", "period", sym, "omega (rad/s)", f"least {sym}", "points", "ends"],
                            rows))
    if res.codim2:
        lines += ["", "Codimension-two points:"]
        rows = [[p.kind, f"{p.omega:.6g}", f"{p.value2:.6g}", res.loci[p.locus].name,
                 ", ".join(f"{a:.4g}" for a in p.amplitude), "" if p.located else "approximate"]
                for p in res.codim2]
        lines.append(_table(["kind", "omega (rad/s)", sym, "curve", f"{', '.join(res.channels)} (m)", "notes"],
                            rows))
    if not res.complete:
        lines += ["", "Interrupted: the curves traced until then are kept (the last one as far as it got)."]
    return "\n".join(lines)


def backbone_summary(case, res, wall: float) -> str:
    """Summary of a backbone: where it starts and ends, how the frequency moved (hardening or
    softening), stability and the internal resonances met."""
    lines = [f"cablesim {__version__}: backbone of mode {res.mode} of '{case.name}' ({res.analysis} analysis, "
             f"unforced, undamped), linear frequency {res.linear_omega:.6g} rad/s",
             f"{res.omega.size} periodic orbits in {wall:.3g} s wall time; {res.end}", ""]
    if res.omega.size:
        peak = res.amplitude.max(axis=1)
        shift = res.omega[-1] - res.linear_omega
        trend = "softening" if shift < 0 else "hardening"
        lines.append(f"Frequency {res.omega[0]:.6g} -> {res.omega[-1]:.6g} rad/s ({trend}, {shift:+.4g} rad/s) as the "
                     f"largest amplitude grows from {peak[0]:.4g} to {peak[-1]:.4g} m; frequency range "
                     f"{res.omega.min():.6g} - {res.omega.max():.6g} rad/s.")
        unstable = int((~res.stable).sum())
        lines.append("Every orbit is stable." if unstable == 0 else
                     f"{unstable} of {res.omega.size} orbits are unstable (a multiplier off the unit circle).")
        rows = []
        for i in np.unique(np.linspace(0, res.omega.size - 1, min(8, res.omega.size)).astype(int)):
            rows.append([f"{res.omega[i]:.6g}", ", ".join(f"{a:.4g}" for a in res.amplitude[i]),
                         "yes" if res.stable[i] else "no"])
        lines += ["", _table(["omega (rad/s)", f"{', '.join(res.channels)} (m)", "stable"], rows)]
    if res.resonances:
        lines += ["", "Internal resonances:"]
        rows = [[r["kind"], f"{r['omega']:.6g}", ", ".join(f"{a:.4g}" for a in r["amplitude"]),
                 "" if r["located"] else "approximate"] for r in res.resonances]
        lines.append(_table(["kind", "omega (rad/s)", f"{', '.join(res.channels)} (m)", "notes"], rows))
    else:
        lines += ["", "No internal resonance met."]
    return "\n".join(lines)
