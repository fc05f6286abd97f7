"""Frequency-response (FDR) plot of a frequency sweep.

Reads the HDF5 file of ``cablesim sweep`` and draws the steady response amplitude (or half
range) of each chosen channel against the forcing frequency. The file layout:

- root attributes ``case_yaml``, ``cablesim_version``, ``command`` (``"sweep"``), ``analysis``;
- group ``/sweep`` with attributes ``direction`` (``"independent"``, ``"up"``, ``"down"`` or
  ``"both"``), ``channels`` (``["z2", "z4"]``), ``case_name``, ``integrator``, ``cap`` (s) and
  ``window`` (s); dataset ``/sweep/omega`` (P,) rad/s, ascending; optional ``/sweep/gamma`` (G,);
- result datasets ``amplitude``, ``halfrange``, ``response_frequency`` ([G,] P, C), ``period``,
  ``steady``, ``done`` ([G,] P), directly in ``/sweep`` for an independent sweep, else in
  ``/sweep/up`` and/or ``/sweep/down``; a leading gamma axis iff ``/sweep/gamma`` exists.
  Points not computed (an interrupted sweep) have ``done`` False and NaN values;
- ``/modal/omega``: the linear modal frequencies, rad/s.

Channels are named as elsewhere in cablesim: ``"z2k - 1"`` / ``"z2k"`` are the horizontal /
vertical (pointing down) displacement of node k. matplotlib is imported lazily through
:func:`cablesim.plotting._plt` (Agg backend).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import CablesimError
from .plot_history import _CHANNEL_RE, _channel_desc, _figure
from .plotting import save_atomic

#: Largest number of channels drawn (one subplot each).
MAX_CHANNELS = 8
#: The quantities that can be plotted, with their axis wording.
QUANTITIES = {"amplitude": "peak |z|", "halfrange": "half range"}
#: Sweep directions and the result groups they use.
_DIRECTION_GROUPS = {"independent": [None], "up": ["up"], "down": ["down"], "both": ["up", "down"]}
#: Curve colours, one per gamma value (red is kept for the non-steady markers).
_COLORS = ["C0", "C1", "C2", "C4", "C5", "C6", "C8", "C9", "C7"]
#: Line style and marker of each sweep direction.
_STYLE = {
    "independent": dict(ls="-", marker="o", ms=3.0, label="independent sweep"),
    "up": dict(ls="-", marker=">", ms=4.0, label="up sweep"),
    "down": dict(ls="--", marker="<", ms=4.0, label="down sweep"),
}


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


@dataclass
class _Curve:
    """One sweep curve: one gamma value (or none) and one direction; arrays over P points."""

    gamma: float | None
    direction: str  # "independent", "up" or "down"
    data: dict  # name -> (P, C) or (P,) array, in ascending omega order

    @property
    def valid(self) -> np.ndarray:
        """Points that were computed (done, with a finite amplitude)."""
        return self.data["done"] & np.all(np.isfinite(self.data["amplitude"]), axis=1)

    @property
    def label(self) -> str:
        g = "" if self.gamma is None else f"gamma = {self.gamma:g}, "
        return f"{g}{self.direction}"


@dataclass
class _Sweep:
    path: Path
    omega: np.ndarray
    channels: list[str]
    direction: str
    analysis: str
    attrs: dict
    gamma: np.ndarray | None
    curves: list[_Curve] = field(default_factory=list)
    modal: np.ndarray = field(default_factory=lambda: np.empty(0))


def _text(value) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        return _text(value.item())
    return str(value)


def _str_list(value) -> list[str]:
    if isinstance(value, (str, bytes)):
        return [_text(value)]
    return [_text(v) for v in np.asarray(value, dtype=object).ravel()]


def _normalise_channel(name) -> str | None:
    """``"z2"``, ``"Z2"``, ``" 2"`` or ``2`` -> ``"z2"``; None if malformed."""
    if isinstance(name, bool):
        return None
    if isinstance(name, numbers.Integral):
        return f"z{int(name)}"
    if isinstance(name, (str, bytes)):
        match = _CHANNEL_RE.match(_text(name))
        if match is not None:
            return f"z{int(match.group(1))}"
    return None


def _read_sweep(h5_path) -> _Sweep:
    import h5py

    path = Path(h5_path)
    if not path.is_file():
        raise CablesimError(f"The sweep file {path} does not exist.")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise CablesimError(f"{path} is not an HDF5 file (or cannot be read): {exc}.") from exc
    with f:
        if "sweep" not in f or not isinstance(f["sweep"], h5py.Group):
            command = _text(f.attrs.get("command", "unknown"))
            raise CablesimError(
                f"{path} is not a sweep file: it has no /sweep group (it was written by the "
                f"'{command}' command). Plot the output of 'cablesim sweep'."
            )
        g = f["sweep"]

        def bad(what: str):
            return CablesimError(f"The sweep file {path} is malformed: {what}.")

        if "omega" not in g:
            raise bad("/sweep/omega is missing")
        omega = np.asarray(g["omega"][()], dtype=float).ravel()
        P = omega.size
        if P == 0:
            raise bad("/sweep/omega is empty")
        order = np.argsort(omega, kind="stable")
        omega = omega[order]

        direction = _text(g.attrs.get("direction", "independent"))
        if direction not in _DIRECTION_GROUPS:
            raise bad(f"unknown sweep direction {direction!r} (expected one of {', '.join(_DIRECTION_GROUPS)})")
        gamma = np.atleast_1d(np.asarray(g["gamma"][()], dtype=float)) if "gamma" in g else None
        G = None if gamma is None else gamma.size

        curves: list[_Curve] = []
        n_chan = None
        for sub in _DIRECTION_GROUPS[direction]:
            where = g if sub is None else g.get(sub)
            name = "/sweep" if sub is None else f"/sweep/{sub}"
            if where is None:
                raise bad(f"direction {direction!r} but the group {name} is missing")
            if "amplitude" not in where:
                raise bad(f"{name}/amplitude is missing")
            raw = {}
            C = None
            for key in ("amplitude", "halfrange", "response_frequency", "period", "steady", "done"):
                if key not in where:
                    continue
                arr = np.asarray(where[key][()])
                if key == "amplitude":
                    C = arr.shape[-1] if arr.ndim >= 2 else 0
                tail = (P, C) if key in ("amplitude", "halfrange", "response_frequency") else (P,)
                if G is not None and arr.ndim == len(tail):  # gamma axis left out for G = 1
                    if G != 1:
                        raise bad(f"{name}/{key} has no gamma axis but /sweep/gamma has {G} values")
                    arr = arr[None]
                want = ((G,) if G is not None else ()) + tail
                if arr.shape != want:
                    raise bad(f"{name}/{key} has shape {arr.shape}, expected {want}")
                raw[key] = np.take(arr, order, axis=0 if G is None else 1)
            if n_chan is not None and C != n_chan:
                raise bad(f"{name} holds {C} channels, another group {n_chan}")
            n_chan = C
            for gi in range(1 if G is None else G):
                data = {k: (v if G is None else v[gi]) for k, v in raw.items()}
                amp = data["amplitude"].astype(float)
                data["amplitude"] = amp
                for key in ("halfrange", "response_frequency"):
                    data[key] = data[key].astype(float) if key in data else np.full_like(amp, np.nan)
                data["period"] = data["period"].astype(int) if "period" in data else np.ones(P, dtype=int)
                data["steady"] = data["steady"].astype(bool) if "steady" in data else np.ones(P, dtype=bool)
                finite = np.all(np.isfinite(amp), axis=1)
                data["done"] = (data["done"].astype(bool) & finite) if "done" in data else finite
                curves.append(_Curve(None if G is None else float(gamma[gi]), sub or "independent", data))

        channels = _str_list(g.attrs["channels"]) if "channels" in g.attrs else [f"z{k + 1}" for k in range(n_chan)]
        if len(channels) != n_chan:
            raise bad(f"the attribute channels names {len(channels)} channels but the results hold {n_chan}")
        channels = [_normalise_channel(c) or c for c in channels]
        analysis = _text(f.attrs.get("analysis", g.attrs.get("analysis", "unknown")))
        attrs = {k: g.attrs[k] for k in ("case_name", "integrator", "cap", "window") if k in g.attrs}
        modal = np.empty(0)
        if "modal" in f and "omega" in f["modal"]:
            modal = np.sort(np.asarray(f["modal"]["omega"][()], dtype=float).ravel())
    return _Sweep(path, omega, channels, direction, analysis, attrs, gamma, curves, modal)


def _select_channels(sweep: _Sweep, channels) -> list[int]:
    """Indices into the file's channel axis of the chosen channels."""
    have = ", ".join(sweep.channels)
    if channels is None:
        return list(range(len(sweep.channels)))
    if isinstance(channels, (str, bytes, numbers.Integral)):
        channels = [channels]
    out: list[int] = []
    for c in channels:
        name = _normalise_channel(c)
        if name is None:
            raise CablesimError(f"Channel name {c!r} is malformed; the sweep file {sweep.path} holds {have}.")
        if name not in sweep.channels:
            raise CablesimError(
                f"Channel {c!r} was not recorded in the sweep file {sweep.path}; it holds {have}. "
                "Choose one of those, or rerun the sweep with the channel."
            )
        i = sweep.channels.index(name)
        if i not in out:
            out.append(i)
    if not out:
        raise CablesimError(f"No channels were chosen to plot; name at least one of {have}.")
    return out


def _check_quantity(quantity: str) -> str:
    if quantity not in QUANTITIES:
        raise CablesimError(f"Unknown quantity {quantity!r}; choose one of {', '.join(QUANTITIES)}.")
    return quantity


# --------------------------------------------------------------------------------------------
# Summary
# --------------------------------------------------------------------------------------------


def sweep_summary_rows(h5_path, quantity: str = "amplitude") -> list[dict]:
    """The largest response of every curve and channel of a sweep file.

    Parameters
    ----------
    h5_path : str or Path
        The HDF5 file written by ``cablesim sweep``.
    quantity : {"amplitude", "halfrange"}, optional
        The quantity whose maximum is sought.

    Returns
    -------
    list of dict
        One row per curve (gamma value, direction) and channel, in file order, with keys
        ``gamma`` (float or None), ``direction`` (``"independent"``, ``"up"`` or ``"down"``),
        ``channel`` (``"z2"``), ``omega`` (forcing frequency of the largest value, rad/s),
        ``value`` (that largest value, m), ``period`` and ``steady`` (at that point),
        ``points_done`` and ``points``. ``omega`` and ``value`` are NaN (``period`` 0,
        ``steady`` False) if no point of the curve was computed.

    Raises
    ------
    CablesimError
        If the file is missing, not HDF5 or not a sweep file, or the quantity is unknown.
    """
    _check_quantity(quantity)
    sweep = _read_sweep(h5_path)
    rows = []
    for curve in sweep.curves:
        valid = curve.valid
        y_all = curve.data[quantity]
        for c, name in enumerate(sweep.channels):
            ok = valid & np.isfinite(y_all[:, c])
            row = dict(gamma=curve.gamma, direction=curve.direction, channel=name,
                       omega=float("nan"), value=float("nan"), period=0, steady=False,
                       points_done=int(valid.sum()), points=int(sweep.omega.size))
            if ok.any():
                k = np.flatnonzero(ok)[np.argmax(y_all[ok, c])]
                row.update(omega=float(sweep.omega[k]), value=float(y_all[k, c]),
                           period=int(curve.data["period"][k]), steady=bool(curve.data["steady"][k]))
            rows.append(row)
    return rows


# --------------------------------------------------------------------------------------------
# The plot
# --------------------------------------------------------------------------------------------


def _runs(mask: np.ndarray, values: np.ndarray):
    """Start indices of the runs of equal ``values`` where ``mask`` holds."""
    starts = []
    prev = None
    for k in range(mask.size):
        if mask[k] and (prev is None or values[k] != values[prev] or prev != k - 1):
            starts.append(k)
        if mask[k]:
            prev = k
    return starts


def _subtitle(sweep: _Sweep, shown: list[str]) -> str:
    d = sweep.direction
    dir_text = {"independent": "independent points", "up": "up sweep", "down": "down sweep",
                "both": "up and down sweeps"}[d]
    parts = [f"channels {', '.join(shown)}", dir_text]
    if sweep.gamma is not None:
        parts.append(f"{sweep.gamma.size} gamma values")
    if "cap" in sweep.attrs:
        cap = f"cap {float(sweep.attrs['cap']):.4g} s per point"
        if "window" in sweep.attrs:
            cap += f" (window {float(sweep.attrs['window']):.4g} s)"
        parts.append(cap)
    if "integrator" in sweep.attrs:
        parts.append(_text(sweep.attrs["integrator"]))
    return ", ".join(parts)


def plot_sweep(h5_path, png_path=None, channels=None, quantity: str = "amplitude", title: str | None = None) -> Path:
    """Draw the frequency response of a sweep file as a PNG.

    One subplot per channel, stacked and sharing the frequency axis: the response amplitude
    (or half range) in metres against the forcing frequency in rad/s. Independent sweeps are
    solid lines with small dots; up sweeps solid lines with ``>`` markers, down sweeps dashed
    lines with ``<`` markers; one colour per gamma value. Points whose response did not become
    steady within the cap are ringed in red; points with a subharmonic response (period of
    2 or more forcing periods) get a black diamond and a ``1/p`` label at the start of each run.
    Linear modal frequencies inside the frequency range are faint dotted lines. Points not
    computed (an interrupted sweep) are left out and counted in a note under the plot.

    Parameters
    ----------
    h5_path : str or Path
        The HDF5 file written by ``cablesim sweep``.
    png_path : str or Path, optional
        PNG to write; default: ``h5_path`` with the suffix ``.png``.
    channels : str or int or sequence of those, optional
        Channels to draw, e.g. ``["z2", "z4"]``; they must have been recorded in the file.
        Default: all recorded channels (at most 8 are drawn).
    quantity : {"amplitude", "halfrange"}, optional
        Peak displacement from the equilibrium, or half the peak-to-peak range.
    title : str, optional
        First title line; default ``"<case_name>: frequency response (<analysis> analysis)"``.

    Returns
    -------
    Path
        The PNG written.

    Raises
    ------
    CablesimError
        If the file is missing, not HDF5 or not a sweep file, a channel is unknown or the
        quantity is unknown.
    """
    from matplotlib.lines import Line2D

    _check_quantity(quantity)
    sweep = _read_sweep(h5_path)
    chans = _select_channels(sweep, channels)
    notes = []
    if len(chans) > MAX_CHANNELS:
        notes.append(f"showing the first {MAX_CHANNELS} of {len(chans)} chosen channels")
        chans = chans[:MAX_CHANNELS]
    png_path = Path(h5_path).with_suffix(".png") if png_path is None else Path(png_path)

    omega = sweep.omega
    P = omega.size
    lo, hi = float(omega[0]), float(omega[-1])
    pad = 0.02 * (hi - lo) if hi > lo else max(0.05 * abs(lo), 0.1)
    x_lo, x_hi = lo - pad, hi + pad
    markevery = max(1, P // 80)

    gammas = [] if sweep.gamma is None else list(sweep.gamma)
    if len(gammas) <= len(_COLORS):
        colors = _COLORS[: max(1, len(gammas))]
    else:
        import matplotlib

        cmap = matplotlib.colormaps["viridis"]
        colors = [cmap(v) for v in np.linspace(0.0, 0.9, len(gammas))]

    def color_of(curve):
        return colors[0] if curve.gamma is None else colors[gammas.index(curve.gamma)]

    modal_k = [(k + 1, w) for k, w in enumerate(sweep.modal) if np.isfinite(w) and x_lo <= w <= x_hi]

    n = len(chans)
    fig, axes = _figure(n, 1, 8.6, 2.6, sharex=True, top=0.8 if modal_k else 0.65, hspace=0.3, left=1.4)
    any_unsteady = any_sub = False
    for ax, c in zip(axes[:, 0], chans):
        name = sweep.channels[c]
        for curve in sweep.curves:
            valid = curve.valid
            y = np.where(valid, curve.data[quantity][:, c], np.nan)
            st = _STYLE[curve.direction]
            col = color_of(curve)
            ax.plot(omega, y, ls=st["ls"], marker=st["marker"], ms=st["ms"], color=col, lw=1.2,
                    markevery=markevery, zorder=2)
            unsteady = valid & ~curve.data["steady"] & np.isfinite(y)
            if unsteady.any():
                any_unsteady = True
                ax.plot(omega[unsteady], y[unsteady], ls="none", marker="o", ms=8, mfc="none",
                        mec="red", mew=1.2, zorder=4)
            period = curve.data["period"]
            sub = valid & (period >= 2) & np.isfinite(y)
            if sub.any():
                any_sub = True
                ax.plot(omega[sub], y[sub], ls="none", marker="D", ms=3.5, color="k", zorder=5)
                for k in _runs(sub, period):
                    ax.annotate(f"1/{period[k]}", (omega[k], y[k]), textcoords="offset points",
                                xytext=(0, 7), ha="center", va="bottom", fontsize=7, color="0.15", zorder=6,
                                bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))
        for _, w in modal_k:
            ax.axvline(w, color="0.5", ls=":", lw=1.0, alpha=0.7, zorder=1)
        ax.set_ylim(bottom=0.0)
        ax.set_ylabel(f"{name} {QUANTITIES[quantity]} (m)\n{_channel_desc(int(name[1:]) - 1)}"
                      if name[1:].isdigit() else f"{name} {QUANTITIES[quantity]} (m)", fontsize=9)
        ax.grid(True, alpha=0.3)
    top_ax = axes[0, 0]
    last_text = -np.inf
    for k, w in modal_k:  # above the top axes; name the lines that have room
        if w - last_text >= 0.09 * (x_hi - x_lo):
            last_text = w
            top_ax.text(w, 1.01, f"w{k} = {w:.4g}", transform=top_ax.get_xaxis_transform(), fontsize=7,
                        color="0.35", ha="center", va="bottom")
    axes[-1, 0].set_xlim(x_lo, x_hi)
    axes[-1, 0].set_xlabel("forcing frequency omega (rad/s)")

    # Legend from proxy artists: colours = gamma values, line styles = directions, markers.
    handles = []
    if gammas:
        shown = list(range(len(gammas))) if len(gammas) <= 12 else [0, len(gammas) - 1]
        for r in shown:
            handles.append(Line2D([], [], color=colors[r], lw=2.5, label=f"gamma = {gammas[r]:g}"))
            if len(shown) == 2 and r == 0:
                handles.append(Line2D([], [], ls="none", label=f"... ({len(gammas) - 2} more)"))
    style_color = "0.3" if gammas else colors[0]
    for d in dict.fromkeys(cv.direction for cv in sweep.curves):
        st = _STYLE[d]
        handles.append(Line2D([], [], ls=st["ls"], marker=st["marker"], ms=st["ms"] + 1, color=style_color,
                              lw=1.2, label=st["label"]))
    handles += marker_handles(any_unsteady, any_sub)
    if modal_k:
        handles.append(Line2D([], [], ls=":", color="0.5", lw=1.0, label="linear modal frequencies"))
    top_ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)

    # Incomplete sweep.
    total = P * len(sweep.curves)
    done = sum(int(cv.valid.sum()) for cv in sweep.curves)
    warn = done < total
    if warn:
        text = f"incomplete sweep: {done} of {total} points"
        short = [f"{cv.label}: {int(cv.valid.sum())} of {P}" for cv in sweep.curves if cv.valid.sum() < P]
        if len(sweep.curves) > 1:
            more = f"; and {len(short) - 4} more curves" if len(short) > 4 else ""
            text += " (" + "; ".join(short[:4]) + more + ")"
        notes.insert(0, text)
    if done == 0:
        top_ax.text(0.5, 0.5, "no computed points", transform=top_ax.transAxes, ha="center",
                    va="center", color="C3", fontsize=10)

    first = title if title is not None else (
        f"{_text(sweep.attrs.get('case_name', sweep.path.stem))}: frequency response ({sweep.analysis} analysis)"
    )
    height = fig.get_figheight()
    fig.suptitle(f"{first}\n{_subtitle(sweep, [sweep.channels[c] for c in chans])}", fontsize=10,
                 y=1 - 0.08 / height, va="top")
    if notes:
        pos = axes[-1, 0].get_position()
        fig.text(0.5 * (pos.x0 + pos.x1), 0.0, "\n".join(notes), ha="center", va="top", fontsize=9,
                 color="red" if warn else "0.3", fontweight="bold" if warn else "normal", wrap=True)
    return save_atomic(fig, png_path)


def marker_handles(any_unsteady: bool, any_sub: bool) -> list:
    """Legend entries for the point markers of a frequency-response plot (those present)."""
    from matplotlib.lines import Line2D

    handles = []
    if any_unsteady:
        handles.append(Line2D([], [], ls="none", marker="o", ms=8, mfc="none", mec="red", mew=1.2,
                              label="not steady (cap reached)"))
    if any_sub:
        handles.append(Line2D([], [], ls="none", marker="D", ms=3.5, color="k",
                              label="subharmonic response (period p >= 2),\nlabelled 1/p"))
    return handles
