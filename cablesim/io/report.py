"""Plain-text summaries printed by the commands."""

from __future__ import annotations

import numpy as np

from ..analyses.records import spectrum_part
from ..case.placement import placements_text
from ..dynamics.extremes import peak_and_half_range
from ..dynamics.spectra import spectrum_peaks
from ..version import __version__
from .continuation import PARAMETER_WORDS, support_meaning


def _table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max([len(h)] + [len(r[i]) for r in rows]) for i, h in enumerate(header)]
    line = lambda cells: "  " + "  ".join(c.rjust(w) for c, w in zip(cells, widths))  # noqa: E731
    return "\n".join([line(header)] + [line(r) for r in rows])


def _g(v: float, digits: int = 6) -> str:
    return f"{v:.{digits}g}"


#: Above this many nodes the static summary shows the first and last few rows of each table.
SUMMARY_NODES = 20
#: Rows kept at each end of a shortened table.
SUMMARY_ENDS = 5


def _shown(count: int, full: bool, ends: int = SUMMARY_ENDS) -> list[int | None]:
    """Row indices to print: all, or the first and last ``ends`` with None for the gap."""
    if full or count <= 2 * ends + 1:
        return list(range(count))
    return [*range(ends), None, *range(count - ends, count)]


def _rows(indices: list[int | None], make, width: int) -> list[list[str]]:
    return [make(i) if i is not None else ["..."] + [""] * (width - 1) for i in indices]


def static_summary(case, result, full: bool = False) -> str:
    """Readable summary of a static analysis: coordinates, tensions, frequencies, damping.

    For cables of more than SUMMARY_NODES nodes the tables show their first and last rows (and
    the lowest modes) unless ``full``.
    """
    c = result.cable
    n = c.n_nodes
    full = full or n <= SUMMARY_NODES
    excess = 100.0 * (c.total_length / c.chord_length - 1.0)
    out = [
        f"cablesim {__version__}: static analysis of '{case.name}' ({result.analysis} analysis)",
        f"cable: n = {n} nodes, L = {_g(c.L)} m, H = {_g(c.H)} m (down), sum S = {_g(c.total_length)} m "
        f"({excess:+.4g} % of the chord {_g(c.chord_length)} m), EA = {c.EA:.4g} N",
    ]
    placed = placements_text(case.placements, (result.exact or result.approximate).y, c.dim)
    out += [placed] if placed else []
    out += ["", "Node coordinates under F0, m (vertical axis pointing down):"]
    header = ["DOF", "F0 (kN)"]
    cols = []
    if result.inextensible is not None:
        header.append("x inextensible")
        cols.append(result.inextensible.x)
    if result.approximate is not None:
        header += ["u approximate", "y approximate"]
        cols += [result.approximate.u, result.approximate.y]
    if result.exact is not None:
        header.append("y exact")
        cols.append(result.exact.y)
    dim = c.dim
    rows = _rows(_shown(dim * n, full, 2 * SUMMARY_ENDS), lambda i: [f"{('xy' if dim == 2 else 'xvw')[i % dim]}{i // dim + 1} ({i + 1})",
                 _g(result.P[i] / 1e3, 6)] + [_g(col[i], 8) for col in cols], len(header))
    out.append(_table(header, rows))

    out += ["", "Segment tensions, kN:"]
    header = ["segment", "S (m)"]
    cols = []
    if result.inextensible is not None:
        header.append("T inextensible")
        cols.append(result.inextensible.T)
    if result.exact is not None:
        header += ["T exact", "strain exact"]
        cols += [result.exact.T, None]
    def segment_row(r):
        row = [str(r + 1), _g(c.S[r])]
        for col in cols:
            row.append(f"{result.exact.T[r] / c.EA:.3e}" if col is None else _g(col[r] / 1e3, 7))
        return row

    out.append(_table(header, _rows(_shown(c.n_segments, full), segment_row, len(header))))

    m = result.modes
    which = "" if m.complete else f"; the lowest {m.omega.size} of {c.n_dof}, highest {_g(m.omega_max, 7)} rad/s"
    out += ["", f"Linear modes about the equilibrium ({result.analysis} tangent stiffness{which}):"]
    modes = range(m.omega.size) if full else range(min(m.omega.size, 2 * SUMMARY_ENDS))
    kind = (lambda k: [m.kinds[k]]) if m.kinds else (lambda k: [])
    rows = [
        [str(k + 1), _g(m.omega[k], 7), _g(m.frequency_hz[k], 6), _g(m.period[k], 6), f"{result.damping_ratios[k]:.4g}"]
        + kind(k)
        for k in modes
    ]
    if len(modes) < m.omega.size:
        rows.append([f"... {m.omega.size - len(modes)} more, up to", _g(m.omega[-1], 7), _g(m.frequency_hz[-1], 6),
                     _g(m.period[-1], 6), f"{result.damping_ratios[-1]:.4g}"] + kind(m.omega.size - 1))
    out.append(_table(["mode", "omega (rad/s)", "f (Hz)", "period (s)", "damping ratio"] + (["kind"] if m.kinds else []),
                      rows))
    if m.kinds:
        out.append("Modes are in-plane or out-of-plane (of the plane of a planar equilibrium) or coupled; "
                   "damping.modes counts the modes that are not out of the plane.")
    out.append(f"Rayleigh damping C = a0 M + a1 K0: a0 = {result.a0:.6g} 1/s, a1 = {result.a1:.6g} s")
    if result.inextensible_omega.size:
        w = ", ".join(_g(v, 7) for v in result.inextensible_omega[:8])
        more = " ..." if result.inextensible_omega.size > 8 else ""
        out.append(f"Inextensible cable (EA -> inf): finite frequencies {w}{more} rad/s")
    if result.sole_inextensible_omega is not None:
        out.append(f"  closed form after eq. 21 (sole inextensible frequency): {_g(result.sole_inextensible_omega, 7)} rad/s")
    if result.approximate is not None:
        a = result.approximate
        out.append(
            f"Complementary energies: Omega_c = T.S = {a.omega_c:.6g} J, Omega_e = {a.omega_e:.6g} J"
        )
    if result.exact is not None:
        out.append(f"Static solver residual (closure error): {result.exact.segments.closure_error:.2e} m")
    if not full:
        out.append(f"(tables shortened for n = {n} nodes; --full prints every row)")
    return "\n".join(out)


def response_peaks(hist, z) -> list[float]:
    """The two strongest frequencies of one channel, rad/s, over the part of the record a
    spectrum reads (:func:`cablesim.analyses.records.spectrum_part`; none if it is too short)."""
    t = np.asarray(hist.t, dtype=float)
    forcing = hist.omega if hist.omega is not None and hist.omega > 0 else None
    part = spectrum_part(t, z, forcing, hist.completed)
    if part.short is not None:
        return []
    peaks = spectrum_peaks(t[part.start:part.stop], z[part.start:part.stop], 1.0, max_peaks=2)
    if forcing is None and len(peaks) and spectrum_part(t, z, None, frequency=float(peaks[0])).short is not None:
        return []
    return list(peaks)


def history_summary(case, hist, integ, wall: float, full: bool = False) -> str:
    """Summary of a time history: status, peak displacements, response frequencies, drift.

    More than 2 SUMMARY_NODES channels are shown as the first and last few unless ``full``.
    """
    forced = f"forcing w = {hist.omega:g} rad/s" if hist.omega is not None else "free vibration"
    lines = [
        f"cablesim {__version__}: '{case.name}', {forced}, {hist.analysis} analysis, "
        f"integrator {integ.name} ({', '.join(f'{k}={v:g}' for k, v in integ.settings().items() if isinstance(v, float))})",
        f"simulated {hist.t[-1]:.6g} s in {wall:.3g} s wall time; status: {hist.message}",
        f"linear modes: {', '.join(f'{w:.5g}' for w in hist.modal_omega[:6])} rad/s",
        "",
    ]
    half = hist.t.size // 2

    def row(i):
        z = hist.z[:, i]
        peaks = response_peaks(hist, z)
        # extremes between the saved instants, from z and its velocity (cablesim.dynamics.extremes)
        peak, _ = peak_and_half_range(hist.t, z, hist.v[:, i])
        _, half_range = peak_and_half_range(hist.t[half:], z[half:], hist.v[half:, i])
        return [
            f"z{hist.dof_numbers[i]}",
            _g(float(peak[0]), 5),
            _g(float(half_range[0]), 5) if half > 0 else "-",
            ", ".join(f"{p:.4g}" for p in peaks) or "-",
        ]

    channels = len(hist.dof_numbers)
    rows = _rows(_shown(channels, full or channels <= 2 * SUMMARY_NODES, 2 * SUMMARY_ENDS), row, 4)
    lines.append(_table(["DOF", "max |z| (m)", "half range, 2nd half (m)", "response peaks (rad/s)"], rows))
    dT = hist.T - hist.T0
    # the peak tensions located between the saved instants, where recorded
    top = dT.max() if hist.slack is None else max(dT.max(), float((hist.slack.peak_tension - hist.T0).max()))
    lines.append(
        f"tension change: min {dT.min() / 1e3:.4g} kN, max {top / 1e3:.4g} kN "
        f"(static {', '.join(f'{t / 1e3:.5g}' for t in hist.T0[:6])} kN)"
    )
    lines.append(f"largest drift of eq. 15 (relative to |F0|): {np.max(hist.residual):.2e}")
    if hist.slack is not None:
        lines += ["", *slack_lines(hist.slack, float(hist.t[-1]), full)]
    return "\n".join(lines)


def slack_lines(rec, duration: float, full: bool = True) -> list[str]:
    """Per segment: peak tension (the snap load) and when, time slack, episodes.

    A cable of more than 2 SUMMARY_NODES segments shows the 2 SUMMARY_ENDS segments slack
    longest (then highest peak tension) unless ``full``.
    """
    count = rec.peak_tension.size
    shown = list(range(count))
    if not full and count > 2 * SUMMARY_NODES:
        order = np.lexsort((-rec.peak_tension, -rec.slack_time))
        shown = sorted(int(k) for k in order[: 2 * SUMMARY_ENDS])
    rows = [
        [f"{k + 1}", _g(rec.peak_tension[k] / 1e3, 6), f"{rec.peak_time[k]:.6g}", f"{rec.slack_time[k]:.4g}",
         f"{100.0 * rec.slack_time[k] / duration:.3g}" if duration > 0 else "-", f"{rec.episodes[k]}"]
        for k in shown
    ]
    out = [_table(["segment", "peak tension (kN)", "at t (s)", "slack (s)", "slack (%)", "slack episodes"], rows)]
    if len(shown) < count:
        out.append(f"({len(shown)} of {count} segments: those slack longest, then of highest peak tension; "
                   "--full prints every segment)")
    if rec.t.size:
        out.append(f"{rec.t.size} slack/taut transitions located; {rec.chatter_holds} chatter holds ({rec.handling})")
    return out


def grid_note(omega, refine, grid_points=None, finest=None) -> str:
    """How a sweep's frequencies were chosen, in words: the grid, and its refinement or the
    warning that it was not refined (a feature narrower than its step can fall between points).

    ``refine`` is the number of halvings allowed (None: unknown, a file of an earlier version);
    ``grid_points`` the points of the grid before refinement.
    """
    omega = np.unique(np.asarray(omega, dtype=float))
    if refine is None or omega.size < 2:
        return ""
    n_grid = int(grid_points) if grid_points is not None else omega.size
    added = omega.size - n_grid
    if int(refine) > 0:
        step = f" to {float(finest):.3g} rad/s" if finest is not None and np.isfinite(finest) else ""
        return (f"grid of {n_grid} frequencies refined{step} where neighbouring points disagree "
                f"({added} added)" if added else f"grid of {n_grid} frequencies; no neighbouring points disagree")
    return (f"grid step up to {float(np.diff(omega).max()):.3g} rad/s, not refined (sweep.refine): "
            "a narrower feature can fall between points")


def sweep_summary(case, res, wall: float, full: bool = False) -> str:
    """Summary of a sweep: points, steady fraction, resonance peaks per curve and channel, and
    every point that stopped early with why (such points hold partial values: never a peak).

    More than 2 SUMMARY_NODES channels are shown as the first and last few unless ``full``;
    so are more than 2 SUMMARY_NODES failed points."""
    lines = [
        f"cablesim {__version__}: sweep of '{case.name}', {res.omega.size} frequencies from "
        f"{res.omega.min():.4g} to {res.omega.max():.4g} rad/s, {len(res.curves)} curve(s), "
        f"{res.n_done} of {res.n_total} points in {wall:.3g} s wall time",
    ]
    st = res.settings
    if "integrator" in st:
        tols = "" if "integrator_rtol" not in st else (
            f" (rtol = {st['integrator_rtol']:g}, atol = {st['integrator_atol']:.3g} m at every point)")
        lines.append(f"integrator {st['integrator']}{tols}")
    grid = grid_note(res.omega, st.get("refine"), st.get("grid_points"), st.get("finest_step"))
    if grid:
        lines.append(f"  {grid}")
    rows = []
    for k, c in enumerate(res.curves):
        d = res.table(k)
        label = c.direction + ("" if res.gamma is None else f", gamma = {res.gamma[c.gamma_index]:g}")
        done = d.done
        if not done.any():
            continue
        good = done & ~d.failed
        many = len(res.channels) > 2 * SUMMARY_NODES
        for j in _shown(len(res.channels), full or not many):
            if j is None:
                rows.append(["...", f"({len(res.channels) - 2 * SUMMARY_ENDS} more channels)", "", ""])
                continue
            name = res.channels[j]
            a = np.where(good & np.isfinite(d.amplitude[:, j]), d.amplitude[:, j], -np.inf)
            if np.isfinite(a).any():
                i = int(np.argmax(a))
                rows.append([label, name, f"{res.omega[i]:.4g}", _g(d.amplitude[i, j], 5)])
            else:
                rows.append([label, name, "-", "no point ran to its end"])
        steady = d.steady[done]
        failed = d.failed[done]
        capped = ~steady & ~failed
        sub = d.period[done] >= 2
        lines.append(
            f"  {label}: {steady.sum()} of {done.sum()} points steady"
            + (f", {sub.sum()} subharmonic (period >= 2)" if sub.any() else "")
            + (f", {capped.sum()} reached the cap" if capped.any() else "")
            + (f", {failed.sum()} FAILED (stopped early; listed below, left out of the peaks)" if failed.any() else "")
        )
        frac = d.slack_fraction
        if frac.size and np.any(frac[done] > 0):
            slack = np.any(frac > 0, axis=1) & done
            worst = np.nanmax(frac[done], axis=0)
            lines.append(
                f"    {slack.sum()} point(s) with slack episodes; largest slack fraction per segment "
                + ", ".join(f"{100.0 * x:.3g} %" for x in worst)
                + "; largest peak tension " + ", ".join(f"{x / 1e3:.4g}" for x in np.nanmax(d.peak_tension[done], axis=0)) + " kN"
            )
    lines.append(_table(["curve", "channel", "peak at (rad/s)", "peak amplitude (m)"], rows))
    failures = res.failures()
    if failures:
        lines += ["", f"{len(failures)} point(s) failed (values partial, not used as peaks):"]
        shown = _shown(len(failures), full or len(failures) <= 2 * SUMMARY_NODES)
        lines += [f"  {failures[k]}" if k is not None else f"  ... ({len(failures) - 2 * SUMMARY_ENDS} more)"
                  for k in shown]
    if not full and (len(res.channels) > 2 * SUMMARY_NODES or len(failures) > 2 * SUMMARY_NODES):
        lines.append("(the first and last rows; --verbose prints every one, /sweep in the file holds them all)")
    return "\n".join(lines)


#: The sense of a node whose path encloses no area: along a line, or a figure of eight whose
#: lobes go round opposite ways (a period-2 whirl: w at half the frequency of v).
NO_NET_ROTATION = "round with no net rotation (zero enclosed area: a line or a figure of eight)"


def _senses_text(senses) -> str:
    """The senses of rotation of a branch's nodes (``whirl_sense`` of its points), in words: one
    sense for every node when they agree, else per node (the first and last few), each with
    "changes along the branch" where a node's points go round both ways."""
    words = []
    for k in range(senses.shape[1]):
        seen = [x for x in dict.fromkeys(senses[:, k]) if x in ("counter-clockwise", "clockwise")]
        words.append(" then ".join(seen) if seen else NO_NET_ROTATION)
    if len(set(words)) == 1:
        if words[0] == NO_NET_ROTATION:
            return f"{'the node goes' if len(words) == 1 else 'every node goes'} {NO_NET_ROTATION}"
        return f"{'the node goes' if len(words) == 1 else 'every node goes'} round {words[0]}"
    shown = [f"node {k + 1} {w}" for k, w in enumerate(words)]
    if len(shown) > 2 * SUMMARY_ENDS:
        shown = shown[:SUMMARY_ENDS] + ["..."] + shown[-SUMMARY_ENDS:]
    return ", ".join(shown)


def _whirling_lines(res) -> list:
    """One line per nonplanar branch of a spatial cable: its largest out-of-plane displacement
    ``|w|`` (which node, where), the sense in which its nodes go round as seen from support A
    looking towards B, and the range of the tilt of its orbits' mean plane; nothing for planar
    branches."""
    out = []
    unit = " rad/s" if res.parameter == "omega" else ""
    for b in res.branches:
        if not getattr(b, "nonplanar", False) or not b.tilt.size:
            continue
        head = f"  {b.name}: nonplanar (whirling){'; its mirror image w -> -w is a branch too' if b.mirror_image else ''}"
        max_w = getattr(b, "max_w", None)
        if max_w is None or not np.any(np.isfinite(max_w)):
            out.append(head + "; its whirling measures could not be computed (no plane of equilibrium)")
            continue
        k, node = np.unravel_index(int(np.nanargmax(max_w)), max_w.shape)
        tilt = b.tilt[np.isfinite(b.tilt)]
        out.append(f"{head}: largest |w| {max_w[k, node]:.4g} m (node {node + 1}, at {res.parameter} "
                   f"{b.parameter[k]:.5g}{unit}); seen from A looking towards B, {_senses_text(b.whirl_sense)}; mean plane "
                   f"tilted {tilt.min():.3g} - {tilt.max():.3g} deg from the cable's plane")
    return ([""] + out) if out else []


def _grazing_note(g) -> str:
    """The notes of a grazing point located on a branch through slack ("" for other points)."""
    if g is None:
        return ""
    return (f"segment {g.segment}: {g.episodes[0]} -> {g.episodes[1]} slack episodes per period; multipliers "
            f"either side differ by up to {g.jump:.3g}")


def _slack_lines(res) -> list:
    """Through slack, one line per branch: how many of its orbits have a slack segment and its
    largest snap load (which segment, where)."""
    out = []
    for b in res.branches:
        sl = getattr(b, "slack", None)
        if sl is None or not sl.peak_tension.size:
            continue
        k, j = np.unravel_index(int(np.argmax(sl.peak_tension)), sl.peak_tension.shape)
        out.append(f"  {b.name}: a segment slack on {int(sl.slack.sum())} of {sl.slack.size} orbits; largest snap load "
                   f"{sl.peak_tension[k, j] / 1e3:.5g} kN (segment {j + 1}, at {res.parameter} {b.parameter[k]:.6g})")
    return ([""] + out) if out else []


def continuation_conditions(res) -> str:
    """The fixed parameters of a continuation in words: ``"omega = 12.08 rad/s, gamma = 1"``."""
    if res.parameter == "omega":
        return f"gamma = {res.fixed:g}"
    fixed = f"omega = {res.fixed:g} rad/s"
    return fixed + (f", gamma = {getattr(res, 'fixed_gamma', 1.0):g}" if res.parameter == "support" else "")


def continuation_summary(case, res, wall: float) -> str:
    """Summary of a continuation: branches, their stable parts, and the bifurcations found."""
    unit = "rad/s" if res.parameter == "omega" else ""
    cost = res.stats
    name = PARAMETER_WORDS["support"] if res.parameter == "support" else res.parameter
    meaning = support_meaning(getattr(res, "support_amplitudes", {})) if res.parameter == "support" else ""
    span = f"from {res.start:g} to {res.stop:g} {unit}".strip()
    lines = [
        f"cablesim {__version__}: continuation of '{case.name}' in {name} {span} "
        f"({continuation_conditions(res)}, {res.analysis} analysis{'; ' + meaning if meaning else ''})",
        f"{len(res.branches)} branch(es), {res.n_points} periodic orbits in {wall:.3g} s wall time"
        + (f" ({cost['evaluations']} shooting evaluations)" if "evaluations" in cost else ""),
        "",
    ]
    rows = []
    for b in res.branches:
        peak = b.amplitude.max(axis=0) if b.amplitude.size else np.zeros(len(res.channels))
        rows.append([b.name, str(b.period), f"{b.parameter.min():.5g} - {b.parameter.max():.5g}",
                     str(b.parameter.size), f"{100.0 * b.stable.mean():.0f} %",
                     ", ".join(f"{p:.4g}" for p in peak), b.end])
    lines.append(_table(["branch", "period", f"range {unit}".strip(), "orbits", "stable",
                         f"max {', '.join(res.channels)} (m)", "ended"], rows))
    lines += _whirling_lines(res) + _slack_lines(res)
    lines += ["", "Bifurcations:" if res.bifurcations else "No bifurcations in the range."]
    spatial = any(b.plane != "in-plane" for b in res.bifurcations) or any(
        b.planes is not None and np.any(b.planes != "in-plane") for b in res.branches)
    if res.bifurcations:
        rows = [[b.kind] + ([b.plane] if spatial else []) + [f"{b.parameter:.6g}", res.branches[b.branch].name if b.branch < len(res.branches) else str(b.branch),
                 str(b.period), ", ".join(f"{a:.4g}" for a in b.amplitude), f"{abs(b.multiplier):.4f}",
                 ("" if b.located else "not located; ") + ("" if b.trusted else "multipliers not trusted")
                 + (f"frequency ratio {b.frequency_ratio:.4f}" if b.kind == "neimark-sacker" else "")
                 + _grazing_note(getattr(b, "grazing", None))]
                for b in sorted(res.bifurcations, key=lambda b: (b.branch, b.parameter))]
        symbol = "s" if res.parameter == "support" else res.parameter
        lines.append(_table(["kind"] + (["plane"] if spatial else []) + [symbol, "branch", "period", f"{', '.join(res.channels)} (m)", "|mu|",
                             "notes"], rows))
    return "\n".join(lines)
