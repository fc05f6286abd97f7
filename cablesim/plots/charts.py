"""Design charts: the stability chart in (omega, gamma) or (omega, s) and backbone curves.

- :func:`plot_stability_chart`: every bifurcation curve of a continuation file with loci, one
  colour per kind (line style per orbit period), the regions they close shaded by what happens
  inside (hysteresis between two fold curves; the harmonic response unstable inside a
  period-doubling tongue or a Neimark-Sacker curve), the codimension-two points marked and named
  (cusps, fold-flip points, strong resonances), and the line of the computed frequency response
  with its bifurcations across the chart. The second parameter is the load factor gamma or the
  support motion multiplier s (its axis then says what s = 1 stands for, and a second axis gives
  the first moving support's amplitude in m).
- :func:`plot_backbone`: a backbone's frequency against its amplitude per channel, stable solid
  and unstable dashed, its internal resonances marked, the linear frequency and the other modes'
  frequencies divided by small integers dotted (where the family can meet them); optionally over
  the frequency-response curves of continuation files, whose peaks it should pass through.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io.charts import read_backbone
from ..io.continuation import read_continuation
from ..errors import CablesimError
from .base import bottom_notes, figure_grid, legend_below, save_atomic, title_line
from .continuation import parameter_axis
from .style import COLOURS, SERIES, styled
from .sweep import channel_label

#: Colour of each kind of curve, and how the region it closes is shaded (label, alpha, hatch).
KIND_STYLE = {
    "fold": ("#1f5fa8", "fold curve (multiplier +1: a jump)", "three harmonic responses: hysteresis, jumps", 0.13, None),
    "period-doubling": ("#d95f02", "period-doubling curve (multiplier -1)",
                        "harmonic response unstable: 1/2 subharmonic", 0.22, None),
    "neimark-sacker": ("#7b3fa0", "Neimark-Sacker curve (complex pair)",
                       "harmonic response unstable: quasi-periodic", 0.18, "//"),
    # a planar response's out-of-plane bifurcations (spatial cables symmetric about their plane)
    "out-of-plane period-doubling": ("#1b9e77", "out-of-plane period-doubling curve (-1 across the plane)",
                                     "planar response unstable across its plane: swings at 1/2", 0.2, "\\\\"),
    "out-of-plane neimark-sacker": ("#e7298a", "out-of-plane Neimark-Sacker curve",
                                    "planar response unstable across its plane: quasi-periodic", 0.16, ".."),
    "out-of-plane pitchfork": ("#66a61e", "pitchfork curve (+1 across the plane: whirling is born)",
                               "planar response unstable across its plane: whirling", 0.18, "xx"),
}
#: Marker and short label of each codimension-two point.
CODIM2_STYLE = {
    "cusp": ("*", "C", "cusp: two fold curves meet (the least forcing that jumps)"),
    "fold-flip": ("X", "FF", "fold-flip: multipliers +1 and -1"),
    "1:1 resonance": ("P", "R1", "1:1 resonance (double multiplier +1)"),
    "1:2 resonance": ("P", "R2", "1:2 resonance (double multiplier -1)"),
    "1:3 resonance": ("P", "R3", "1:3 resonance"),
    "1:4 resonance": ("P", "R4", "1:4 resonance"),
    "fold-neimark-sacker": ("h", "FNS", "fold-Neimark-Sacker"),
    "flip-neimark-sacker": ("h", "PNS", "flip-Neimark-Sacker"),
    "generalized period doubling": ("d", "GPD", "generalized period doubling: the period doubling\n"
                                    "changes from sub- to supercritical (approximate)"),
}
#: Line style of the curves of orbits of each period (period 1 first).
PERIOD_LINES = ("-", "--", ":", "-.")


def style_key(kind: str, plane: str) -> str:
    """The :data:`KIND_STYLE` entry of a curve of ``kind`` whose critical multiplier lies in
    ``plane`` (``in-plane`` or ``out-of-plane``)."""
    key = f"out-of-plane {kind}" if plane == "out-of-plane" else kind
    return key if key in KIND_STYLE else kind


def _closed_polygons(x: np.ndarray, y: np.ndarray, box) -> list:
    """The curve closed along the chart's boundary both ways round when both its ends lie on it,
    the smaller enclosed area first (empty otherwise)."""
    x0, x1, y0, y1 = box
    tol = 1e-6

    def side(px, py):
        for k, (v, ref, span) in enumerate(((py, y0, y1 - y0), (px, x1, x1 - x0), (py, y1, y1 - y0),
                                            (px, x0, x1 - x0))):
            if abs(v - ref) <= tol * max(span, 1e-300):
                return k
        return None

    if x.size < 3 or side(x[-1], y[-1]) is None or side(x[0], y[0]) is None:
        return []
    corners = [(x1, y0), (x1, y1), (x0, y1), (x0, y0)]  # ends of sides 0 (bottom), 1, 2, 3 going round

    def walk(k_from, k_to, step):
        out, k = [], k_from
        while k != k_to:
            out.append(corners[k] if step == 1 else corners[(k - 1) % 4])
            k = (k + step) % 4
        return out

    a, b = side(x[-1], y[-1]), side(x[0], y[0])
    out = []
    for step in (1, -1):
        pts = np.vstack([np.column_stack([x, y]), np.array(walk(a, b, step)).reshape(-1, 2)])
        area = 0.5 * abs(np.dot(pts[:, 0], np.roll(pts[:, 1], -1)) - np.dot(pts[:, 1], np.roll(pts[:, 0], -1)))
        out.append((area, step, pts))
    return [pts for _, _, pts in sorted(out, key=lambda t: (t[0], t[1]))]


def _inside(poly: np.ndarray, px: np.ndarray, py: float) -> np.ndarray:
    """Even-odd rule: which of the points ``(px, py)`` lie inside the polygon."""
    inside = np.zeros(px.size, dtype=bool)
    xs, ys = poly[:, 0], poly[:, 1]
    for i in range(len(poly)):
        xa, ya, xb, yb = xs[i - 1], ys[i - 1], xs[i], ys[i]
        if (ya > py) != (yb > py):
            xc = xa + (py - ya) * (xb - xa) / (yb - ya)
            inside ^= px < xc
    return inside


def _confirmed(kind: str, poly: np.ndarray, d: dict) -> bool:
    """Whether the frequency response confirms what the shading of a region says where its line
    crosses the region (unstable harmonic orbits inside it); a region it does not cross is
    shaded on the curves' word."""
    g0 = float(d["loci"]["response"])
    b1 = [b for b in d["branches"] if b["period"] == 1]
    if not b1 or not (poly[:, 1].min() < g0 < poly[:, 1].max()):
        return True
    w = np.concatenate([b["omega"] for b in b1])
    stable = np.concatenate([b["stable"] for b in b1]).astype(bool)
    inside = _inside(poly, w, g0)
    return not inside.any() or bool((~stable[inside]).any())


def _draw_loci(ax, d: dict, box) -> tuple[set, set]:
    """Curves, shaded regions and codimension-two points; the kinds and the shadings drawn."""
    kinds, shaded = set(), set()
    for L in d["loci"]["loci"]:
        key = style_key(L["kind"], L.get("plane", "in-plane"))
        colour, _, region, alpha, hatch = KIND_STYLE[key]
        ls = PERIOD_LINES[min(int(np.log2(L["period"])), len(PERIOD_LINES) - 1)]
        ax.plot(L["omega"], L["values2"], ls, color=colour, lw=1.6, zorder=3)
        kinds.add((key, L["period"]))
        # the region the curve closes: the smaller way round unless the computed response
        # says otherwise (a tongue reaching both sides of the chart is closed over its top)
        polys = _closed_polygons(L["omega"], L["values2"], box) if L["period"] == 1 else []
        poly = next((q for q in polys if _confirmed(L["kind"], q, d)), None)
        if poly is not None:
            ax.fill(poly[:, 0], poly[:, 1], color=colour, alpha=alpha, hatch=hatch, lw=0, zorder=1)
            shaded.add(key)
    return kinds, shaded


def _draw_codim2(ax, c2: dict, sym: str) -> set:
    drawn = set()
    for k, kind in enumerate(c2["kind"]):
        marker, short, _ = CODIM2_STYLE.get(kind, ("o", kind, kind))
        x, y = float(c2["omega"][k]), float(c2["values2"][k])
        ax.plot(x, y, marker, color=COLOURS["annotation"], mfc="white", ms=7, mew=1.0, zorder=6)
        ax.annotate(f"{short}\n{x:.4g} rad/s, {sym} {y:.3g}", (x, y), textcoords="offset points", xytext=(6, -4),
                    fontsize=8, va="top", zorder=7)
        drawn.add(kind)
    return drawn


def _draw_thresholds(ax, d: dict, sym: str) -> bool:
    """The least gamma (or s) of each period-1 period-doubling or Neimark-Sacker curve (its
    turning point: the least forcing at which the harmonic response loses stability there)."""
    drawn = False
    for L in d["loci"]["loci"]:
        if L["kind"] == "fold" or L["period"] != 1:
            continue
        y2 = L["values2"]
        for k, sp in enumerate(L["special"]):
            if sp == "turning point" and y2[k] <= y2.min() * (1 + 1e-9):
                x, y = float(L["omega"][k]), float(y2[k])
                ax.plot(x, y, "v", color=KIND_STYLE[style_key(L["kind"], L.get("plane", "in-plane"))][0], mfc="white",
                        ms=6, zorder=6)
                # left of the point and below: codimension-two labels go to its right
                ax.annotate(f"least {sym} = {y:.3g}\nat {x:.4g} rad/s", (x, y), textcoords="offset points",
                            xytext=(-6, -6), ha="right", va="top", fontsize=8, zorder=7)
                drawn = True
    return drawn


def _draw_response_line(ax, d: dict, lo: float, hi: float) -> None:
    """The frequency response's line across the chart, with its bifurcations."""
    g0 = float(d["loci"]["response"])
    ax.axhline(g0, color=COLOURS["reference"], lw=1.0, ls=(0, (5, 2)), zorder=2)
    bif = d["bifurcations"]
    planes = bif.get("plane", ["in-plane"] * len(bif["kind"]))
    for k, kind in enumerate(bif["kind"]):
        if kind in KIND_STYLE:
            ax.plot(float(bif["omega"][k]), g0, "o", ms=3.5, color=KIND_STYLE[style_key(kind, planes[k])][0], zorder=5)


def _second_axis(d: dict) -> tuple[str, str, str]:
    """The y-axis label, the symbol of the curves' second parameter and the response's
    conditions in words."""
    lc = d["loci"]
    at = float(lc["response"])
    if lc["parameter"] == "support":
        label, sym, _ = parameter_axis({**d, "parameter": "support"})
        return label, sym, f"{sym} = {at:g}, $\\gamma$ = {float(d['fixed']):g}"
    return "load factor $\\gamma$ (multiplies $F_L$)", "$\\gamma$", f"$\\gamma$ = {at:g}"


def _metres_axis(ax, d: dict) -> None:
    """A right-hand axis of a chart in s: the first moving support's amplitude, ``s |u|`` in m."""
    amplitudes = d.get("support_amplitudes", {})
    if not amplitudes:
        return
    name, u = next(iter(amplitudes.items()))
    a = float(np.linalg.norm(u))
    right = ax.secondary_yaxis("right", functions=(lambda s: s * a, lambda y: y / a))
    right.set_ylabel(f"support amplitude $s\\,|u_{name}|$ (m)")


def _draw_modal_lines(ax, d: dict, lo: float, hi: float, top: float) -> None:
    """The natural frequencies and their doubles within the chart (primary and principal
    parametric resonances)."""
    for k, w in enumerate(d["modal"]):
        if lo <= w <= hi:
            ax.axvline(w, color=COLOURS["reference"], ls=":", lw=0.9, zorder=1)
            ax.annotate(f"$\\omega_{{{k + 1}}}$", (w, top), textcoords="offset points", xytext=(2, -10), fontsize=8)
        if lo <= 2 * w <= hi:
            ax.axvline(2 * w, color=COLOURS["reference"], ls=":", lw=0.9, zorder=1)
            ax.annotate(f"$2\\omega_{{{k + 1}}}$", (2 * w, top), textcoords="offset points", xytext=(2, -10),
                        fontsize=8)


@styled
def plot_stability_chart(h5_path, png_path=None, title: str | None = None) -> Path:
    """Draw the stability chart of a continuation file with bifurcation curves as a PNG.

    Parameters
    ----------
    h5_path : str or Path
        Written by ``cablesim continue`` with ``continuation.loci``.
    png_path : str or Path, optional
        Default: ``<h5_path stem>-chart.png`` beside it.
    title : str, optional
        Default ``"<case name>: stability chart"``.

    Returns
    -------
    Path

    Raises
    ------
    CablesimError
        If the file holds no bifurcation curves.
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    h5_path = Path(h5_path)
    d = read_continuation(h5_path)
    lc = d["loci"]
    if lc is None:
        raise CablesimError(f"{h5_path} holds no bifurcation curves; run cablesim continue with "
                            "continuation.loci: true and a range {start, stop} of gamma (or, with moving supports, "
                            "of support) to draw a stability chart.")
    png_path = h5_path.with_name(h5_path.stem + "-chart.png") if png_path is None else Path(png_path)
    lo, hi = sorted((float(d["start"]), float(d["stop"])))
    g_lo, g_hi = sorted((float(lc["start"]), float(lc["stop"])))
    ylabel, sym, response = _second_axis(d)
    box = (lo, hi, g_lo, g_hi)
    fig, axes = figure_grid(1, 1, 4.2, extra_height=1.9)
    ax = axes[0, 0]
    kinds, shaded = _draw_loci(ax, d, box)
    marks = _draw_codim2(ax, lc["codim2"], sym)
    thresholds = _draw_thresholds(ax, d, sym)
    _draw_response_line(ax, d, lo, hi)
    _draw_modal_lines(ax, d, lo, hi, g_hi)
    ax.set_xlim(lo, hi)
    pad = 0.04 * (g_hi - g_lo)  # so that a response line on a bound of the range shows
    ax.set_ylim(g_lo - pad, g_hi + pad)
    ax.set_xlabel("forcing frequency $\\omega$ (rad/s)")
    ax.set_ylabel(ylabel)
    if lc["parameter"] == "support":
        _metres_axis(ax, d)
    handles = [Line2D([], [], color=KIND_STYLE[k][0], ls=PERIOD_LINES[min(int(np.log2(p)), 3)], lw=1.8,
                      label=KIND_STYLE[k][1] + (f", orbits of period {p}T" if p > 1 else ""))
               for k, p in sorted(kinds, key=lambda kp: (list(KIND_STYLE).index(kp[0]), kp[1]))]
    handles += [Patch(color=KIND_STYLE[k][0], alpha=KIND_STYLE[k][3] + 0.1, hatch=KIND_STYLE[k][4],
                      label=KIND_STYLE[k][2]) for k in KIND_STYLE if k in shaded]
    handles += [Line2D([], [], ls="none", marker=CODIM2_STYLE[k][0], color=COLOURS["annotation"], mfc="white", ms=7,
                       label=f"{CODIM2_STYLE[k][1]}: {CODIM2_STYLE[k][2]}") for k in CODIM2_STYLE if k in marks]
    if thresholds:
        handles.append(Line2D([], [], ls="none", marker="v", color=COLOURS["annotation"], mfc="white", ms=6,
                              label=f"least {sym} of a tongue"))
    handles.append(Line2D([], [], color=COLOURS["reference"], ls=(0, (5, 2)), marker="o", ms=3.5,
                          label=f"frequency response computed ({response}) and its bifurcations"))
    legend_below(fig, handles, ncol=2 if max(len(h.get_label()) for h in handles) <= 60 else 1)
    notes = [] if lc["complete"] else ["interrupted: the curves traced until then are drawn"]
    bottom_notes(fig, notes, warn=bool(notes))
    n = len(lc["loci"])
    sub = (f"{d['analysis']} analysis; curves continued over {sym} = {g_lo:g} to {g_hi:g} from the bifurcations "
           f"of the response at {response}; {n} curve{'s' if n != 1 else ''}, "
           f"{len(lc['codim2']['kind'])} codimension-two point{'s' if len(lc['codim2']['kind']) != 1 else ''}")
    title_line(fig, title or f"{d['case_name']}: stability chart", sub)
    return save_atomic(fig, png_path)


# ----------------------------------------------------------------------------------------------
def _draw_backbone(ax, bb: dict, c: int) -> None:
    w, a = bb["omega"], bb["amplitude"][:, c]
    stable = bb["stable"].astype(bool)
    colour = COLOURS["annotation"]
    for mask, ls, lw in ((stable, "-", 2.0), (~stable, "--", 1.4)):
        y = np.where(mask, a, np.nan)
        ax.plot(w, y, ls, color=colour, lw=lw, zorder=5)
    rs = bb["resonances"]
    for k, kind in enumerate(rs["kind"]):
        ax.plot(float(rs["omega"][k]), float(rs["amplitude"][k, c]), "D", color=COLOURS["failure"], mfc="white",
                ms=5, zorder=6)
        ax.annotate(kind.split()[0] + f" (mode {int(rs['mode'][k])})", (float(rs["omega"][k]),
                    float(rs["amplitude"][k, c])), textcoords="offset points", xytext=(5, 4), fontsize=8, zorder=7)


def _draw_responses(ax, conts: list, c_name: str) -> set:
    """The response branches of continuation files (one colour per file); the labels drawn."""
    labels = set()
    for i, d in enumerate(conts):
        if c_name not in d["channels"]:
            continue
        c = d["channels"].index(c_name)
        colour = SERIES[i % len(SERIES)]
        for b in d["branches"]:
            if d["parameter"] != "omega":
                continue
            x, y = b["omega"], b["amplitude"][:, c]
            st = b["stable"].astype(bool)
            ax.plot(x, np.where(st, y, np.nan), "-", color=colour, lw=1.2, zorder=3)
            ax.plot(x, np.where(~st, y, np.nan), "--", color=colour, lw=0.9, zorder=2)
        labels.add(i)
    return labels


def _submultiples(bb: dict, lo: float, hi: float) -> list:
    """(label, omega) of the other modes' frequencies over 1..6 within the frequency range."""
    out = []
    for j in bb["other_modes"]:
        wj = float(bb["modal"][j - 1])
        for k in range(1, 7):
            if lo <= wj / k <= hi:
                out.append((f"$\\omega_{{{j}}}$" + (f"/{k}" if k > 1 else ""), wj / k))
    return out


@styled
def plot_backbone(h5_path, png_path=None, responses=(), title: str | None = None) -> Path:
    """Draw a backbone file, optionally over the frequency responses of continuation files.

    Parameters
    ----------
    h5_path : str or Path
        Written by ``cablesim backbone``.
    png_path : str or Path, optional
        Default: ``h5_path`` with the suffix ``.png``.
    responses : sequence of str or Path
        Continuation files (in omega) of the same cable, drawn under the backbone.
    title : str, optional

    Returns
    -------
    Path
    """
    from matplotlib.lines import Line2D

    bb = read_backbone(h5_path)
    conts = [read_continuation(p) for p in responses]
    png_path = Path(h5_path).with_suffix(".png") if png_path is None else Path(png_path)
    chans = bb["channels"][:8]
    fig, axes = figure_grid(len(chans), 1, 2.0, sharex=True, extra_height=1.9)
    ws = [bb["omega"]] + [b["omega"] for d in conts for b in d["branches"] if d["parameter"] == "omega"]
    lo, hi = float(min(w.min() for w in ws if w.size)), float(max(w.max() for w in ws if w.size))
    pad = 0.05 * max(hi - lo, 1e-3 * hi)
    lo, hi = lo - pad, hi + pad
    drawn = set()
    for c, (ax, name) in enumerate(zip(axes[:, 0], chans)):
        drawn |= _draw_responses(ax, conts, name)
        _draw_backbone(ax, bb, c)
        ax.axvline(bb["linear_omega"], color=COLOURS["reference"], ls=":", lw=1.0, zorder=1)
        for label, w in _submultiples(bb, lo, hi):
            ax.axvline(w, color=COLOURS["forcing"], ls=":", lw=0.9, zorder=1)
            if c == 0:
                ax.annotate(label, (w, 1.0), xycoords=("data", "axes fraction"), textcoords="offset points",
                            xytext=(2, -10), fontsize=8)
        ax.set_ylim(bottom=0.0)
        ax.set_ylabel(channel_label(name, components=bb.get("components", 2)))
    axes[-1, 0].set_xlim(lo, hi)
    axes[-1, 0].set_xlabel("frequency $\\omega$ (rad/s): of the free orbit (backbone), of the forcing (responses)"
                           if conts else "frequency $\\omega$ of the free orbit (rad/s)")
    k = bb["mode"]
    handles = [Line2D([], [], color=COLOURS["annotation"], lw=2.0, label=f"backbone of mode {k}: free undamped orbits")]
    if not bb["stable"].all():
        handles.append(Line2D([], [], color=COLOURS["annotation"], lw=1.4, ls="--", label="backbone: unstable orbits"))
    if len(bb["resonances"]["kind"]):
        handles.append(Line2D([], [], ls="none", marker="D", color=COLOURS["failure"], mfc="white",
                              label="internal resonance k:l with mode j (its frequency k/l times the orbit's)"))
    handles.append(Line2D([], [], color=COLOURS["reference"], ls=":", label=f"linear frequency $\\omega_{{{k}}}$"))
    if _submultiples(bb, lo, hi):
        handles.append(Line2D([], [], color=COLOURS["forcing"], ls=":",
                              label="other modes' linear frequencies over 1..6 (internal resonances)"))
    for i in sorted(drawn):
        d = conts[i]
        handles.append(Line2D([], [], color=SERIES[i % len(SERIES)], lw=1.2,
                              label=f"forced response, $\\gamma$ = {float(d['fixed']):g} (dashed: unstable)"))
    legend_below(fig, handles, ncol=2)
    notes = [] if bb["complete"] else ["interrupted: the orbits computed until then are drawn"]
    bottom_notes(fig, notes, warn=bool(notes))
    sub = (f"{bb['analysis']} analysis; unforced, undamped cable from mode {k} "
           f"($\\omega_{{{k}}}$ = {bb['linear_omega']:.5g} rad/s) up to {bb['amplitude_max']:g} m; "
           f"{bb['omega'].size} orbits; {bb['end']}")
    title_line(fig, title or f"{bb['case_name']}: backbone of mode {k}", sub)
    return save_atomic(fig, png_path)
