"""HDF5 output.

Files are written atomically: into ``NAME.part`` beside the target, then renamed over it, so a
failed or interrupted run never leaves a corrupt or half-written result under the real name.
Every dataset carries a ``units`` attribute; non-finite numbers are refused unless a caller
says explicitly that they mark missing values.
"""

from __future__ import annotations

import datetime as _dt
import os
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np

from . import __version__


@contextmanager
def atomic_h5(path: str | Path, mode: str = "w"):
    """Open ``path`` for writing via a temporary file renamed into place on success.

    Parameters
    ----------
    path : str or Path
        Final file name; its folder is created if needed.
    mode : str
        ``"w"`` starts empty; ``"a"`` starts from a copy of the existing file.

    Yields
    ------
    h5py.File
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    if mode == "a" and path.exists():
        import shutil

        shutil.copyfile(path, tmp)
    try:
        with h5py.File(tmp, "a" if mode == "a" else "w") as f:
            yield f
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def stamp(f: h5py.File, case_text: str, command: str, **attrs) -> None:
    """Root attributes every cablesim file has: the case, the version, the command."""
    f.attrs["case_yaml"] = case_text
    f.attrs["cablesim_version"] = __version__
    f.attrs["command"] = command
    f.attrs["created_utc"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    for k, v in attrs.items():
        f.attrs[k] = v


def put(group: h5py.Group, name: str, data, units: str, description: str = "", allow_nan: bool = False):
    """Write one dataset with its units (and an optional description).

    Raises
    ------
    ValueError
        If ``data`` holds NaN or infinity and ``allow_nan`` is False.
    """
    arr = np.asarray(data)
    if arr.dtype.kind == "f" and not allow_nan and not np.all(np.isfinite(arr)):
        raise ValueError(f"refusing to write non-finite values to {group.name}/{name}")
    ds = group.create_dataset(name, data=arr)
    ds.attrs["units"] = units
    if description:
        ds.attrs["description"] = description
    return ds


def write_static(path: str | Path, result, case_text: str) -> Path:
    """Write a :class:`~cablesim.analyses.static.StaticResult` to HDF5.

    Layout: ``/static/inextensible/{x,T,B,D}``, ``/static/approximate/{x,u,y,T,B,D,f,N,K}``,
    ``/static/exact/{y,T,K}``, ``/modal/{omega,shapes,damping_ratio}`` with attributes
    ``analysis``, ``a0``, ``a1``; the case YAML and the version as root attributes.
    """
    path = Path(path)
    r = result
    with atomic_h5(path) as f:
        stamp(f, case_text, "static", analysis=r.analysis)
        st = f.create_group("static")
        put(st, "P", r.P, "N", "sustained loads F0 in DOF order")
        if r.inextensible is not None:
            g = st.create_group("inextensible")
            put(g, "x", r.inextensible.x, "m", "node coordinates of the inextensible cable")
            put(g, "T", r.inextensible.T, "N", "segment tensions")
            put(g, "B", r.inextensible.B, "1", "tangent transformation dT/dP")
            put(g, "D", r.inextensible.D, "m/N", "configurational flexibility dx/dP")
            g.attrs["omega_c"] = r.inextensible.omega_c
        if r.approximate is not None:
            a = r.approximate
            g = st.create_group("approximate")
            for name, val, units, desc in [
                ("x", a.x, "m", "natural-state coordinates x(P)"),
                ("u", a.u, "m", "elastic displacements (eq. 7)"),
                ("y", a.y, "m", "deformed coordinates y = x + u"),
                ("T", a.T, "N", "segment tensions"),
                ("B", a.B, "1", "tangent transformation dT/dP"),
                ("D", a.D, "m/N", "configurational flexibility"),
                ("f", a.f, "m/N", "elastic flexibility (eq. 8)"),
                ("N", a.N, "m/N", "elasto-configurational flexibility D + f"),
                ("K", a.K, "N/m", "tangent stiffness N^-1"),
            ]:
                put(g, name, val, units, desc)
            g.attrs["omega_c"] = a.omega_c
            g.attrs["omega_e"] = a.omega_e
        if r.exact is not None:
            g = st.create_group("exact")
            put(g, "y", r.exact.y, "m", "deformed node coordinates")
            put(g, "T", r.exact.T, "N", "segment tensions EA (l - S) / S")
            put(g, "l", r.exact.length, "m", "stretched segment lengths")
            put(g, "K", r.exact.K, "N/m", "tangent stiffness of the deformed configuration")
        m = f.create_group("modal")
        put(m, "omega", r.modes.omega, "rad/s", "linear modal frequencies, ascending")
        put(m, "shapes", r.modes.shapes, "1/sqrt(kg)", "mass-normalised mode shapes (columns)")
        put(m, "damping_ratio", r.damping_ratios, "1", "Rayleigh damping ratio of each mode")
        put(m, "inextensible_omega", r.inextensible_omega, "rad/s", "finite frequencies of the inextensible cable")
        m.attrs["analysis"] = r.analysis
        m.attrs["a0"] = r.a0
        m.attrs["a1"] = r.a1
        if r.sole_inextensible_omega is not None:
            m.attrs["sole_inextensible_omega"] = r.sole_inextensible_omega
    return path


def write_history(path: str | Path, hist, case_text: str, command: str, extra_attrs: dict | None = None) -> Path:
    """Write a :class:`~cablesim.dynamics.result.HistoryResult` to HDF5.

    Layout: ``/history/{t,z,v,zc,ze,T,residual}`` (time along the first axis, DOF along the
    second), ``/history/y0``, ``/history/T0``, ``/modal/omega``; attributes ``omega``,
    ``analysis``, ``integrator``, ``status`` and the integrator's settings on ``/history``.
    """
    with atomic_h5(path) as f:
        stamp(f, case_text, command, analysis=hist.analysis)
        g = f.create_group("history")
        put(g, "t", hist.t, "s", "saved instants")
        put(g, "z", hist.z, "m", "displacement from the static equilibrium, z = y - y(0) (DOF order)")
        put(g, "v", hist.v, "m/s", "velocity y'")
        if hist.zc is not None:
            put(g, "zc", hist.zc, "m", "configurational part x(P(t)) - x(P(0)) (eq. 22)")
            put(g, "ze", hist.ze, "m", "elastic part of z (eq. 22)")
        put(g, "T", hist.T, "N", "segment tensions")
        put(g, "residual", hist.residual, "1", "drift of eq. 15 relative to |F0|")
        put(g, "dof", np.array(hist.dof_numbers), "1", "1-based DOF number of each column of z, v, zc, ze")
        put(g, "y0", hist.y0, "m", "static equilibrium the displacements are measured from")
        put(g, "T0", hist.T0, "N", "tensions at that equilibrium")
        g.attrs["omega"] = np.nan if hist.omega is None else hist.omega
        g.attrs["forced"] = hist.omega is not None
        g.attrs["analysis"] = hist.analysis
        g.attrs["integrator"] = hist.integrator
        g.attrs["status"] = hist.status
        g.attrs["completed"] = hist.completed
        for k, v in hist.settings.items():
            g.attrs[k] = v
        for k, v in (extra_attrs or {}).items():
            g.attrs[k] = v
        m = f.create_group("modal")
        put(m, "omega", hist.modal_omega, "rad/s", "linear modal frequencies about the equilibrium")
    return Path(path)


def write_sweep(path: str | Path, res, static, case_name: str, case_text: str, sweep) -> Path:
    """Write a (possibly incomplete) :class:`~cablesim.analyses.sweep.SweepResult` atomically.

    Layout: ``/sweep/omega``, optional ``/sweep/gamma`` (then every result dataset has a
    leading gamma axis); for ``independent`` sweeps ``/sweep/{amplitude, halfrange, period,
    steady, response_frequency, t_end, floquet, done}``, for up/down sweeps the same under
    ``/sweep/up/`` and ``/sweep/down/``; ``/modal/omega``. Points not yet computed have
    ``done = False`` and NaN in the float datasets; a point that stopped early (``failed``) may
    have NaN response frequencies. These marked gaps are the only NaN cablesim writes.
    """
    units = {
        "amplitude": ("m", "peak |z| from the static equilibrium"),
        "halfrange": ("m", "half the peak-to-peak range"),
        "response_frequency": ("rad/s", "dominant response frequency"),
        "period": ("forcing periods", "response period p (0: no periodic response found)"),
        "steady": ("1", "whether a stable periodic response was found before the cap"),
        "failed": ("1", "whether the run stopped early (slack segment, blow-up); its values are partial"),
        "t_end": ("s", "simulated time used"),
        "floquet": ("1", "largest Floquet multiplier modulus of the last periodic orbit checked"),
        "done": ("1", "whether the point has been computed"),
        "wall": ("s", "wall-clock time of the point"),
    }
    with atomic_h5(path) as f:
        stamp(f, case_text, "sweep", analysis=static.analysis)
        g = f.create_group("sweep")
        put(g, "omega", res.omega, "rad/s", "forcing frequencies")
        if res.gamma is not None:
            put(g, "gamma", res.gamma, "1", "scale of the harmonic loads FL")
        g.attrs["direction"] = res.direction
        g.attrs["channels"] = np.array(res.channels, dtype="S")
        g.attrs["case_name"] = case_name
        g.attrs["cap"] = sweep.duration
        g.attrs["window"] = sweep.window
        g.attrs["tol"] = sweep.tol
        g.attrs["max_period"] = sweep.max_period
        g.attrs["floquet_check"] = sweep.floquet
        g.attrs["complete"] = res.complete
        g.attrs["points_done"] = res.n_done
        g.attrs["points_total"] = res.n_total
        dirs = sorted({c.direction for c in res.curves}, key=["independent", "up", "down"].index)
        for d in dirs:
            target = g if d == "independent" else g.create_group(d)
            cs = [k for k, c in enumerate(res.curves) if c.direction == d]
            for name, (u, desc) in units.items():
                arrs = [res.data[k][name] for k in cs]
                arr = np.stack(arrs) if res.gamma is not None else arrs[0]
                put(target, name, arr, u, desc, allow_nan=True)
        m = f.create_group("modal")
        put(m, "omega", static.modes.omega, "rad/s", "linear modal frequencies about the equilibrium")
    return Path(path)
