"""Tests of the frequency-response plot of a sweep file (synthetic HDF5 files)."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

import cablesim.plots.sweep as ps
from cablesim.errors import CablesimError
from cablesim.io.sweeps import sweep_summary_rows
from cablesim.plots.sweep import plot_sweep

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
MODAL = [2.524, 4.1, 7.9, 30.0]  # 30 rad/s lies outside every sweep below
W0, ZETA = 2.524, 0.03


def resonance(omega, w0=W0, zeta=ZETA, scale=0.01):
    """Amplitude of a linear oscillator; its peak lies at w0 sqrt(1 - 2 zeta^2)."""
    return scale * w0**2 / np.sqrt((w0**2 - omega**2) ** 2 + (2 * zeta * w0 * omega) ** 2)


def _results(omega, amp, *, steady=None, period=None, done=None):
    """Result datasets of one curve; amp has shape ([G,] P, C)."""
    amp = np.array(amp, dtype=float)
    lead = amp.shape[:-1]
    done = np.ones(lead, bool) if done is None else np.asarray(done, bool)
    amp[~done] = np.nan
    hr = 0.9 * amp
    rf = np.where(done, 1.0, np.nan)[..., None] * omega[:, None] * np.ones(amp.shape)
    return dict(
        amplitude=amp,
        halfrange=hr,
        response_frequency=rf,
        period=np.where(done, 1, 0) if period is None else np.asarray(period),
        steady=done.copy() if steady is None else np.asarray(steady, bool),
        done=done,
    )


def write_sweep(path, omega, groups, *, direction="independent", channels=("z2", "z4"), gamma=None,
                case_name="demo", analysis="exact", channel_dtype=None):
    """Write a sweep file; ``groups`` maps None (independent) or "up"/"down" to result dicts."""
    with h5py.File(path, "w") as f:
        f.attrs["case_yaml"] = "name: demo\n"
        f.attrs["cablesim_version"] = "0.1.0"
        f.attrs["command"] = "sweep"
        f.attrs["analysis"] = analysis
        g = f.create_group("sweep")
        g.attrs["direction"] = direction
        g.attrs["channels"] = np.array(channels, dtype=channel_dtype or h5py.string_dtype())
        g.attrs["case_name"] = case_name
        g.attrs["integrator"] = "newmark"
        g.attrs["cap"] = 600.0
        g.attrs["window"] = 60.0
        g.create_dataset("omega", data=omega)
        if gamma is not None:
            g.create_dataset("gamma", data=np.asarray(gamma, float))
        for sub, data in groups.items():
            where = g if sub is None else g.create_group(sub)
            for k, v in data.items():
                where.create_dataset(k, data=v)
        f.create_group("modal").create_dataset("omega", data=np.asarray(MODAL))
    return path


def two_channel(omega, scale=0.01):
    return np.stack([resonance(omega, scale=scale), 0.5 * resonance(omega, w0=4.1, scale=scale)], axis=-1)


@pytest.fixture
def figures(monkeypatch):
    """Record what every figure holds just before it is saved."""
    seen = []
    real = ps.save_atomic

    def spy(fig, path, *a, **k):
        axes = [ax for ax in fig.axes if ax.get_visible()]
        legends = [ax.get_legend() for ax in axes if ax.get_legend()] + list(fig.legends)
        legend_texts = [t.get_text() for lg in legends for t in lg.get_texts()]
        texts = [t.get_text() for ax in axes for t in ax.texts] + [t.get_text() for t in fig.texts]
        texts += [lg.get_title().get_text() for lg in legends if lg.get_title().get_text()]
        seen.append(dict(
            n_axes=len(axes),
            ylabels=[ax.get_ylabel() for ax in axes],
            legend=legend_texts,
            texts=texts,
            title=fig._suptitle.get_text() if fig._suptitle else "",
            n_lines=[len(ax.lines) for ax in axes],
            markers=[ln.get_marker() for ax in axes for ln in ax.lines],
            lines=[(ln.get_marker(), np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float))
                   for ax in axes for ln in ax.lines],
            width=fig.get_figwidth(),
        ))
        return real(fig, path, *a, **k)

    monkeypatch.setattr(ps, "save_atomic", spy)
    return seen


def _is_png(path):
    return path.is_file() and path.stat().st_size > 1000 and path.read_bytes()[:8] == PNG_MAGIC


# --------------------------------------------------------------------------------------------
# Files of each kind
# --------------------------------------------------------------------------------------------


def test_independent_without_gamma_default_path(tmp_path, figures):
    omega = np.linspace(1.0, 6.0, 121)
    h5 = write_sweep(tmp_path / "fdr.h5", omega, {None: _results(omega, two_channel(omega))})
    out = plot_sweep(h5)
    assert out == tmp_path / "fdr.png"
    assert _is_png(out)
    (fig,) = figures
    assert fig["n_axes"] == 2
    assert fig["ylabels"][0].startswith("$z_{2}$: peak $|z|$ (m)")
    assert "vertical" in fig["ylabels"][0]
    assert fig["title"].splitlines()[0] == "demo: frequency response"
    sub = fig["title"].splitlines()[1]
    assert "exact analysis (newmark)" in sub and "from rest at each frequency" in sub
    assert "at most 600 s per point" in sub
    assert fig["title"].count("exact analysis") == 1
    assert "from rest at each frequency" in fig["legend"]
    assert fig["width"] == 7.0
    # 121 frequencies: a plain line, no marker on every few computed points.
    assert set(fig["markers"]) <= {"None", "none", ""}
    # Modal frequencies in range are named; 30 rad/s is out of range.
    assert {"$\\omega_{1}$ = 2.524", "$\\omega_{2}$ = 4.1"} <= set(fig["texts"])
    assert not any(t.startswith("$\\omega_{4}") for t in fig["texts"])
    assert not any("incomplete" in t for t in fig["texts"])
    assert "not steady within the time limit" not in fig["legend"]  # nothing to mark


def test_independent_with_gamma_and_halfrange(tmp_path, figures):
    omega = np.linspace(1.0, 6.0, 60)
    gamma = [0.5, 1.0, 2.0]
    amp = np.stack([two_channel(omega, scale=0.01 * g) for g in gamma])  # (3, P, 2)
    h5 = write_sweep(tmp_path / "g.h5", omega, {None: _results(omega, amp)}, gamma=gamma)
    out = plot_sweep(h5, tmp_path / "sub" / "g-half.png", quantity="halfrange", title="My title")
    assert out == tmp_path / "sub" / "g-half.png" and _is_png(out)
    (fig,) = figures
    assert [t for t in fig["legend"] if "gamma" in t] == ["$\\gamma$ = 0.5", "$\\gamma$ = 1", "$\\gamma$ = 2"]
    assert fig["title"].splitlines()[0] == "My title"
    assert "gamma" not in fig["title"]  # the legend names the values
    assert "o" in fig["markers"]  # 60 frequencies: each computed point marked
    assert "half range" in fig["ylabels"][0]
    rows = sweep_summary_rows(h5)
    assert len(rows) == 3 * 2
    assert [r["gamma"] for r in rows] == [0.5, 0.5, 1.0, 1.0, 2.0, 2.0]
    assert all(r["direction"] == "independent" for r in rows)
    # The amplitude scales with gamma, the peak frequency does not.
    z2 = [r for r in rows if r["channel"] == "z2"]
    assert [r["value"] for r in z2] == pytest.approx([0.5 * z2[1]["value"], z2[1]["value"], 2 * z2[1]["value"]])
    assert len({r["omega"] for r in z2}) == 1


def test_both_directions_with_jump(tmp_path, figures):
    """Hardening-like hysteresis: the up sweep stays on the large branch up to 3.2 rad/s, the
    down sweep jumps up only at 2.8 rad/s; non-steady points at the jumps, a 1/2 subharmonic
    window on the up sweep."""
    omega = np.linspace(1.5, 5.0, 71)
    base = 0.2 * two_channel(omega)
    big = 0.08 * np.exp(-(((omega - 3.0) / 0.6) ** 2))[:, None] * np.array([1.0, 0.6])
    up_amp = base + np.where(omega[:, None] <= 3.2, big, 0.0)
    down_amp = base + np.where(omega[:, None] <= 2.8, big, 0.0)
    up_period = np.where((omega > 2.0) & (omega < 2.3), 2, 1)
    up_steady = np.abs(omega - 3.25) > 0.04
    down_steady = np.abs(omega - 2.75) > 0.04
    groups = {
        "up": _results(omega, up_amp, steady=up_steady, period=up_period),
        "down": _results(omega, down_amp, steady=down_steady),
    }
    h5 = write_sweep(tmp_path / "both.h5", omega, groups, direction="both", case_name="jumpy")
    out = plot_sweep(h5, tmp_path / "both.png")
    assert _is_png(out)
    (fig,) = figures
    legend = fig["legend"]
    for label in ("increasing frequency (from the previous state)", "decreasing frequency (from the previous state)",
                  "not steady within the time limit", "linear modal frequencies"):
        assert label in legend
    assert any(t.startswith("subharmonic response (period p > 1)") for t in legend)
    assert "1/2" in fig["texts"]
    assert "increasing and decreasing frequency" in fig["title"]
    rows = sweep_summary_rows(h5)
    assert [(r["direction"], r["channel"]) for r in rows] == [("up", "z2"), ("up", "z4"), ("down", "z2"), ("down", "z4")]
    up_z2, down_z2 = rows[0], rows[2]
    # Where the branches differ, the up sweep is higher.
    jump = (omega > 2.8) & (omega <= 3.2)
    assert np.all(up_amp[jump, 0] > down_amp[jump, 0] + 0.01)
    assert up_z2["value"] >= down_z2["value"]
    assert up_z2["steady"] and up_z2["period"] == 1


def test_incomplete_sweep_note_and_summary(tmp_path, figures):
    omega = np.linspace(1.0, 6.0, 50)
    done = np.ones(50, bool)
    done[:20] = False  # a down sweep interrupted after 30 points (it starts at the top)
    groups = {"down": _results(omega, two_channel(omega), done=done)}
    h5 = write_sweep(tmp_path / "part.h5", omega, groups, direction="down")
    assert _is_png(plot_sweep(h5))
    (fig,) = figures
    assert "incomplete sweep: 30 of 50 points" in fig["texts"]
    assert "decreasing frequency (from the previous state)" in fig["legend"]
    rows = sweep_summary_rows(h5)
    assert all(r["points_done"] == 30 and r["points"] == 50 for r in rows)
    assert all(np.isfinite(r["value"]) for r in rows)
    # The z2 resonance (2.524 rad/s) lies below the computed points: its peak is the lowest
    # computed point; the z4 resonance (4.1 rad/s) was reached.
    assert rows[0]["omega"] == pytest.approx(omega[20])
    assert abs(rows[1]["omega"] - 4.1) < 0.06


def test_incomplete_with_several_curves_lists_the_short_ones(tmp_path, figures):
    omega = np.linspace(1.0, 6.0, 20)
    done = np.ones((2, 20), bool)
    done[1, 12:] = False
    amp = np.stack([two_channel(omega), two_channel(omega)])
    h5 = write_sweep(tmp_path / "p2.h5", omega, {None: _results(omega, amp, done=done)}, gamma=[1.0, 2.0])
    plot_sweep(h5)
    note = [t for t in figures[0]["texts"] if t.startswith("incomplete")]
    assert note == ["incomplete sweep: 32 of 40 points (gamma = 2, independent: 12 of 20)"]


def test_nothing_computed_still_plots(tmp_path, figures):
    omega = np.linspace(1.0, 6.0, 10)
    h5 = write_sweep(tmp_path / "none.h5", omega, {None: _results(omega, two_channel(omega), done=np.zeros(10, bool))})
    assert _is_png(plot_sweep(h5))
    assert "incomplete sweep: 0 of 10 points" in figures[0]["texts"]
    rows = sweep_summary_rows(h5)
    assert all(np.isnan(r["omega"]) and r["points_done"] == 0 for r in rows)


# --------------------------------------------------------------------------------------------
# Channels and errors
# --------------------------------------------------------------------------------------------


@pytest.fixture
def simple(tmp_path):
    omega = np.linspace(1.0, 6.0, 30)
    return write_sweep(tmp_path / "s.h5", omega, {None: _results(omega, two_channel(omega))})


@pytest.mark.parametrize("chosen", ["z4", ("Z4", 4, " z4")])
def test_channel_selection_by_name(simple, tmp_path, figures, chosen):
    out = plot_sweep(simple, tmp_path / "z4.png", channels=chosen)
    assert _is_png(out)
    (fig,) = figures
    assert fig["n_axes"] == 1
    assert fig["ylabels"][0].startswith("$z_{4}$: ")


def test_fixed_length_byte_channel_names(tmp_path, figures):
    omega = np.linspace(1.0, 6.0, 20)
    h5 = write_sweep(tmp_path / "b.h5", omega, {None: _results(omega, two_channel(omega))}, channel_dtype="S")
    plot_sweep(h5, channels="z4")
    assert figures[0]["ylabels"][0].startswith("$z_{4}$: ")
    assert [r["channel"] for r in sweep_summary_rows(h5)] == ["z2", "z4"]


def test_channel_order_follows_the_request(simple, figures):
    plot_sweep(simple, channels=["z4", "z2"])
    assert [y.split(":")[0] for y in figures[0]["ylabels"]] == ["$z_{4}$", "$z_{2}$"]


def test_unknown_channel_is_a_clear_error(simple, tmp_path):
    with pytest.raises(CablesimError) as err:
        plot_sweep(simple, channels=["z2", "z3"])
    msg = str(err.value)
    assert "'z3'" in msg and "z2, z4" in msg and "s.h5" in msg
    with pytest.raises(CablesimError, match="malformed"):
        plot_sweep(simple, channels=["node2"])
    with pytest.raises(CablesimError, match="No channels"):
        plot_sweep(simple, channels=[])
    assert not (tmp_path / "s.png").exists()


def test_unknown_quantity(simple):
    with pytest.raises(CablesimError, match="amplitude, halfrange"):
        plot_sweep(simple, quantity="velocity")
    with pytest.raises(CablesimError, match="quantity"):
        sweep_summary_rows(simple, quantity="phase")


def test_not_a_sweep_file_names_the_file(tmp_path):
    path = tmp_path / "history.h5"
    with h5py.File(path, "w") as f:
        f.attrs["command"] = "history"
        f.create_group("history")
    with pytest.raises(CablesimError) as err:
        plot_sweep(path)
    assert str(path) in str(err.value) and "no /sweep group" in str(err.value) and "'history'" in str(err.value)
    with pytest.raises(CablesimError, match="no /sweep group"):
        sweep_summary_rows(path)


def test_missing_and_non_hdf5_files(tmp_path):
    with pytest.raises(CablesimError, match="does not exist"):
        plot_sweep(tmp_path / "nope.h5")
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    with pytest.raises(CablesimError, match="not an HDF5 file") as err:
        plot_sweep(junk)
    assert str(junk) in str(err.value)


def test_malformed_shapes_are_reported(tmp_path):
    omega = np.linspace(1.0, 6.0, 10)
    res = _results(omega, two_channel(omega))
    res["period"] = res["period"][:5]
    h5 = write_sweep(tmp_path / "bad.h5", omega, {None: res})
    with pytest.raises(CablesimError, match="period has shape"):
        plot_sweep(h5)
    h5 = write_sweep(tmp_path / "bad2.h5", omega, {None: _results(omega, two_channel(omega))}, direction="both")
    with pytest.raises(CablesimError, match="/sweep/up is missing"):
        plot_sweep(h5)


# --------------------------------------------------------------------------------------------
# sweep_summary_rows
# --------------------------------------------------------------------------------------------


def test_summary_peak_of_a_resonance_curve(tmp_path):
    omega = np.linspace(1.0, 4.0, 301)  # step 0.01 rad/s
    amp = np.stack([resonance(omega), resonance(omega, w0=3.3)], axis=-1)
    h5 = write_sweep(tmp_path / "res.h5", omega, {None: _results(omega, amp)})
    rows = sweep_summary_rows(h5)
    assert [r["channel"] for r in rows] == ["z2", "z4"]
    for r, w0 in zip(rows, (W0, 3.3)):
        w_peak = w0 * np.sqrt(1 - 2 * ZETA**2)
        assert abs(r["omega"] - w_peak) <= 0.005 + 1e-12  # nearest grid point
        assert r["value"] == pytest.approx(resonance(r["omega"], w0=w0))
        assert r["value"] == pytest.approx(0.01 / (2 * ZETA * np.sqrt(1 - ZETA**2)), rel=2e-3)
        assert r["gamma"] is None and r["direction"] == "independent"
        assert r["points_done"] == r["points"] == 301


def test_summary_unsorted_omega_is_sorted(tmp_path):
    omega = np.linspace(1.0, 4.0, 31)
    perm = np.random.default_rng(0).permutation(31)
    amp = np.stack([resonance(omega), resonance(omega)], axis=-1)
    h5 = write_sweep(tmp_path / "perm.h5", omega[perm], {None: _results(omega[perm], amp[perm])})
    rows = sweep_summary_rows(h5)
    assert rows[0]["omega"] == pytest.approx(omega[np.argmax(amp[:, 0])])


def test_failed_points_are_never_peaks_nor_part_of_a_curve(tmp_path, figures):
    """A point that stopped early (a segment went slack) keeps its partial amplitude in the file,
    but the summary never quotes it as a peak and the plot never joins it into the curve."""
    from cablesim import api
    from cablesim.analyses.sweep import new_sweep_result
    from cablesim.analyses.sweep_points import SweepPoint
    from cablesim.dynamics.status import Status
    from cablesim.io.sweeps import read_sweep, write_sweep

    case = api.load_case(None, ["sweep.omega=[2.0, 2.4, 2.8]", "sweep.channels=[z2]"])
    res = new_sweep_result(case, case.text)
    for i, (amp, failed) in enumerate([(0.5, False), (38.8, True), (0.7, False)]):
        res.add(SweepPoint.from_json({
            "curve": 0, "index": i, "omega": float(res.omega[i]), "amplitude": [amp], "halfrange": [amp],
            "response_frequency": [None if failed else float(res.omega[i])], "period": 0 if failed else 1,
            "steady": not failed, "t_end": 29.0 if failed else 600.0, "floquet": None,
            "status": "stopped" if failed else "steady", "code": int(Status.SLACK if failed else Status.COMPLETED),
            "final_state": [0.0] * 12, "wall": 0.1,
        }, len(res.channels), res.n_dof))
    path = write_sweep(tmp_path / "failed.h5", res)
    curve = read_sweep(path).curves[0]
    assert list(curve.valid) == [True, False, True] and list(curve.failed) == [False, True, False]
    row = sweep_summary_rows(path)[0]
    assert row["value"] == pytest.approx(0.7) and row["omega"] == pytest.approx(2.8)
    png = plot_sweep(path, tmp_path / "failed.png")
    assert png.stat().st_size > 10_000
    # read back from the figure: the curve skips the failed point, a grey cross marks it
    (fig,) = figures
    curve = [(x, y) for m, x, y in fig["lines"] if m in ("o", "None", "none", "") and x.size >= 3]
    assert curve and all(38.8 not in y for _, y in curve)
    crosses = [(x, y) for m, x, y in fig["lines"] if m == "x"]
    assert [list(y) for _, y in crosses] == [[38.8]]
    assert "stopped early: a segment went slack\n(partial value, not a peak)" in fig["legend"]


def test_points_that_went_slack_are_marked(tmp_path):
    """A sweep of the exact analysis continues through slack episodes; the points whose steady
    orbit has a slack segment (FL x 13.5 at 2.45 rad/s: segment 3 once a period) are read back as
    such (from /sweep/slack_fraction) and marked."""
    from cablesim import api
    from cablesim.io.sweeps import read_sweep

    case = api.load_case(None, ["loads.FL=[-81.0e3, 297.0e3, -243.0e3, 1620.0e3]", "sweep.omega=[1.0, 2.45]",
                                "sweep.duration=600", "sweep.window=50", "sweep.channels=[z2]"])
    out = tmp_path / "slack.h5"
    run = api.sweep(case, jobs=1, output=out)
    frac = run.result.data[0]["slack_fraction"]
    curve = read_sweep(out).curves[0]
    assert list(curve.data["went_slack"]) == list((np.nan_to_num(frac) > 0).any(axis=1))
    assert curve.data["went_slack"][1] and not curve.data["went_slack"][0]
    assert run.result.data[0]["steady"][1]
    assert plot_sweep(out, tmp_path / "slack.png").stat().st_size > 10_000


def test_a_small_subharmonic_band_gets_an_inset(tmp_path, monkeypatch):
    """A 1/2 subharmonic band at 5 rad/s a few percent of the main resonance, or as high as the
    resonance but narrow, is drawn again in an inset on its own scale, with its edges to the
    grid step; a band both high and wide needs none."""
    from matplotlib.figure import Figure

    from cablesim.case.sections import FigureSpec
    from cablesim.plots.composite import draw_figure

    seen = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        seen.append([(ax.get_xlim(), [c.get_title() for c in ax.child_axes])
                     for ax in self.axes])
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    omega = np.round(np.linspace(1.0, 6.0, 101), 10)  # 0.05 rad/s steps
    narrow = (omega >= 4.95) & (omega <= 5.1)
    for size, band, insets in ((0.02, narrow, 1), (2.0, narrow, 1), (2.0, (omega >= 4.0) & (omega <= 5.5), 0)):
        amp = two_channel(omega)
        amp[band] = size * amp.max(axis=0)
        h5 = write_sweep(tmp_path / f"sub{len(seen)}.h5", omega, {None: _results(omega, amp, period=np.where(band, 2, 1))})
        draw_figure(FigureSpec(kind="fdr", channels=["z2"]), [h5], tmp_path / f"sub{len(seen)}.png")
        (row,) = seen[-1][:1]
        assert len(row[1]) == insets
    assert seen[0][0][1] == ["subharmonic band 4.95\u20135.10 rad/s (step 0.05)"]


def test_fdr_of_two_cables_draws_each_files_modal_frequencies(tmp_path, monkeypatch):
    """Files of different cables (an approximate and an exact analysis) have different linear
    frequencies: each file's modal lines are drawn in its curve's colour, at its own frequencies,
    and named in the legend; files of one cable share one grey set."""
    from matplotlib.colors import to_hex
    from matplotlib.figure import Figure

    from cablesim.case.sections import FigureSpec
    from cablesim.plots.composite import draw_figure

    seen = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        ax = self.axes[0]
        vlines = [(float(ln.get_xdata()[0]), to_hex(ln.get_color())) for ln in ax.lines
                  if ln.get_linestyle() == ":" and np.ptp(ln.get_xdata()) == 0]
        curves = {to_hex(ln.get_color()) for ln in ax.lines if ln.get_linestyle() == "-"}
        texts = [t.get_text() for lg in self.legends for t in lg.get_texts()]
        seen.append((vlines, curves, texts))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    omega = np.round(np.linspace(1.0, 6.0, 101), 10)
    a = write_sweep(tmp_path / "a.h5", omega, {None: _results(omega, two_channel(omega))})
    b = write_sweep(tmp_path / "b.h5", omega, {None: _results(omega, two_channel(omega))})
    spec = FigureSpec(kind="fdr", channels=["z2"], labels=["approximate", "exact"])
    draw_figure(spec, [a, b], tmp_path / "same.png")
    vlines, curves, texts = seen[-1]
    in_range = [w for w in MODAL if 0.9 <= w <= 6.1]
    assert sorted(w for w, _ in vlines) == pytest.approx(sorted(in_range))
    assert not {c for _, c in vlines} & curves
    assert sum("linear modal frequencies" in t for t in texts) == 1

    with h5py.File(b, "a") as f:
        f["modal/omega"][...] = 1.1 * np.asarray(MODAL)
    draw_figure(spec, [a, b], tmp_path / "two.png")
    vlines, curves, texts = seen[-1]
    shifted = [1.1 * w for w in MODAL if 0.9 <= 1.1 * w <= 6.1]
    assert sorted(w for w, _ in vlines) == pytest.approx(sorted(in_range + shifted))
    colours = {c for _, c in vlines}
    assert len(colours) == 2 and colours <= curves
    assert [t for t in texts if "linear modal" in t] == [
        "linear modal frequencies of approximate (" + ", ".join(f"{w:.4g}" for w in in_range) + " rad/s)",
        "linear modal frequencies of exact (" + ", ".join(f"{w:.4g}" for w in shifted) + " rad/s)"]
