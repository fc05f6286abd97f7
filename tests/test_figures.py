"""`cablesim plot`: redrawing figures from stored results, without recomputing anything.

Real result files come from short runs of the paper example through the Typer app in-process
(a 30 s history at w = 2.4 rad/s, one at 2.5 rad/s, one that kept only z2 and no split, a short
free vibration, a 3-point sweep capped at 200 s, the statics). The composite figures are then
selected by rewriting the `figure:` section of the case stored in a copy of a file (the root
attribute `case_yaml`), which is what a scene's case file would have stored.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from cablesim.case import example_text, parse_case
from cablesim.cli import app
from cablesim.errors import CablesimError
from cablesim.io.hdf5 import read_case_text, read_history
from cablesim.plots.history import plot_history
from cablesim.plots.redraw import redraw

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
HISTORY_SUFFIXES = ["waveforms", "phase", "lissajous", "tensions", "fft"]


def _case_text(figure: str = "", outputs: str = "") -> str:
    text = example_text()
    text = text.replace("{start: 0.5, stop: 6.0, num: 56}", "[1.5, 2.5, 3.5]")
    text = text.replace("duration: 3000.0", "duration: 200.0").replace("window: 200.0 ", "window: 50.0 ")
    assert "[1.5, 2.5, 3.5]" in text and "window: 50.0" in text
    text = text.replace("  omega: 2.4 ", "  omega: 2.4 ", 1).replace("  duration: 600.0 ", "  duration: 30.0 ", 1)
    assert "  duration: 30.0 " in text
    # the history and free-vibration channels of the example go: these results choose their own
    text = "".join(line for line in text.splitlines(keepends=True) if "DOF plotted" not in line)
    if outputs:
        text += "\noutputs:\n" + outputs
    if figure:
        text += "\nfigure:\n" + figure
    return text


def _invoke(*args):
    res = CliRunner().invoke(app, [str(a) for a in args])
    return res.exit_code, res.stdout, res.stderr, res.exception


def _ok(res):
    code, out, err, exc = res
    assert code == 0, (out, err, exc)
    return out


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """Real result files of short runs (computed once for the module)."""
    root = tmp_path_factory.mktemp("results")
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(root)
        (root / "case.yaml").write_text(_case_text(figure="  kind: waveform_phase\n  title: Late jump\n"))
        (root / "z2.yaml").write_text(_case_text(figure="  kind: waveform\n",
                                                 outputs="  channels: [z2]\n  split: false\n"))
        _ok(_invoke("history", "case.yaml", "--no-plot", "-o", "full.h5"))
        _ok(_invoke("history", "case.yaml", "--omega", 2.5, "--no-plot", "-o", "w25.h5"))
        # Plots drawn by the history command itself: z2 only (plot_history with result.dof).
        out = _ok(_invoke("history", "z2.yaml", "-o", "z2only.h5"))
        assert "z2only-waveforms.png" in out and "lissajous" not in out
        _ok(_invoke("free-vibration", "case.yaml", "--mode", 3, "--peak-velocity", 1, "--damping-ratio", 0.2,
                    "--duration", 5, "--no-plot", "-o", "fv.h5"))
        _ok(_invoke("sweep", "case.yaml", "--jobs", 3, "--no-plot", "-o", "sweep.h5"))
        _ok(_invoke("static", "case.yaml", "--no-plot", "-o", "static.h5"))
    return root


@pytest.fixture
def work(tmp_path, monkeypatch, results):
    """cwd = tmp_path, and any attempt to compute (statics, time integration, sweep) fails."""
    import cablesim.analyses.dynamic as dynamic
    import cablesim.analyses.static as static
    import cablesim.analyses.sweep as sweep
    import cablesim.dynamics.simulate as history

    def forbidden(*args, **kwargs):
        raise AssertionError("cablesim plot must not recompute anything")

    monkeypatch.setattr(history, "simulate", forbidden)
    monkeypatch.setattr(dynamic, "simulate", forbidden)
    monkeypatch.setattr(dynamic, "run_static", forbidden)
    monkeypatch.setattr(static, "run_static", forbidden)
    monkeypatch.setattr(sweep, "run_sweep", forbidden)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def with_figure(results: Path, src: str, dst: Path, figure: str | None) -> Path:
    """Copy a result file, replacing the `figure:` section of its stored case (None: remove it)."""
    shutil.copyfile(results / src, dst)
    with h5py.File(dst, "a") as f:
        text = re.sub(r"\nfigure:\n(?:[ \t]+.*(?:\n|$))*", "\n", f.attrs["case_yaml"])
        f.attrs["case_yaml"] = text + ("" if figure is None else "\nfigure:\n" + figure)
    return dst


def check_png(path: Path, min_size: int = 10_000):
    data = Path(path).read_bytes()
    assert data[:8] == PNG_MAGIC
    assert len(data) > min_size
    assert not list(Path(path).parent.glob("*.part*"))


def check_error(res, *words):
    code, out, err, exc = res
    assert code == 2, (out, err, exc)
    assert isinstance(exc, SystemExit)  # a clean exit, no traceback
    assert err.startswith("error: ")
    flat = " ".join(err.split())
    for w in words:
        assert w in flat, (w, flat)
    return flat


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["full.h5", "z2only.h5", "fv.h5"])
def test_read_history_round_trips_the_file(results, name):
    path = results / name
    hist = read_history(path)
    with h5py.File(path, "r") as f:
        g = f["history"]
        for key in ("t", "z", "v", "T", "residual", "y0", "T0"):
            np.testing.assert_array_equal(getattr(hist, key), g[key][()], err_msg=key)
        for key in ("zc", "ze"):
            if key in g:
                np.testing.assert_array_equal(getattr(hist, key), g[key][()], err_msg=key)
            else:
                assert getattr(hist, key) is None
        assert hist.dof_numbers == tuple(int(d) for d in g["dof"][()])
        np.testing.assert_array_equal(hist.modal_omega, f["modal/omega"][()])
        assert hist.integrator == g.attrs["integrator"]
        assert hist.analysis == g.attrs["analysis"] == "exact"
        assert hist.settings["output_step"] == g.attrs["output_step"]
        assert hist.settings["a1"] == g.attrs["a1"]
        for k in ("omega", "status", "analysis", "integrator", "forced", "completed"):
            assert k not in hist.settings
    assert hist.completed
    if name == "fv.h5":
        assert hist.omega is None and hist.zc is not None
        assert hist.settings["duration"] == 5.0
    elif name == "full.h5":
        assert hist.omega == 2.4 and hist.dof is None and hist.n_dof == 4
        assert hist.settings["duration"] == 30.0
    else:
        assert hist.dof == (2,) and hist.z.shape[1] == 1 and hist.zc is None and hist.ze is None


def test_read_case_text_and_wrong_file_type(results):
    text = read_case_text(results / "full.h5")
    case = parse_case(text)
    assert case.figure.kind == "waveform_phase" and case.history.omega == 2.4
    with pytest.raises(CablesimError, match="sweep file"):
        read_history(results / "sweep.h5")


# --------------------------------------------------------------------------------------------
# Composite figures
# --------------------------------------------------------------------------------------------

KINDS = {
    "waveform": "  kind: waveform\n  title: Waveforms\n  channels: [z2, z4]\n  time_window: [10, 30]\n",
    "waveform_phase": "  kind: waveform_phase\n  title: z2 waveform and phase plot\n  labels: [w = 2.4, w = 2.5]\n",
    "waveform_fft": "  kind: waveform_fft\n  channels: [z4]\n",
    "split": "  kind: split\n  title: Configurational and elastic parts\n  channels: [z4]\n",
    "lissajous_tension": "  kind: lissajous_tension\n  pair: [z2, z4]\n  segments: [1, 3]\n",
}


@pytest.mark.parametrize("kind", list(KINDS))
def test_plot_composite_figure(work, results, kind):
    a = with_figure(results, "full.h5", work / "a.h5", KINDS[kind])
    b = with_figure(results, "w25.h5", work / "b.h5", None)  # only the first file's figure counts
    out = _ok(_invoke("plot", a, b, "-o", f"{kind}.png"))
    assert f"{kind}.png" in out
    check_png(work / f"{kind}.png", 30_000)
    assert sorted(p.name for p in work.glob("*.png")) == [f"{kind}.png"]


def test_plot_figure_default_path_and_free_vibration_column(work, results):
    # History and free-vibration files mix in one figure; the PNG goes beside the first file.
    a = with_figure(results, "full.h5", work / "scene.h5", "  kind: waveform_phase\n")
    fv = with_figure(results, "fv.h5", work / "fv.h5", None)
    out = _ok(_invoke("plot", a, fv))
    assert "scene.png" in out
    check_png(work / "scene.png")
    assert redraw([a]) == [a.with_suffix(".png")]  # the Python API, same default


def test_plot_fdr_from_sweep_files(work, results):
    a = with_figure(results, "sweep.h5", work / "s1.h5", "  kind: fdr\n  title: Two sweeps\n  labels: [one, two]\n")
    b = with_figure(results, "sweep.h5", work / "s2.h5", None)
    _ok(_invoke("plot", a, b, "-o", "fdr.png"))
    check_png(work / "fdr.png")


def test_plot_with_a_figure_file(work, results):
    # `--figure FILE.yaml` (as `make fig7b` uses) overrides the stored case's figure section.
    (work / "fig.yaml").write_text(
        "# how to draw it\nfigure:\n  kind: lissajous_tension\n  title: From a figure file\n"
        "  pair: [z2, z4]\n  segments: [1]\n  labels: [\"mode 1\", \"mode 2\"]\n"
    )
    a = with_figure(results, "full.h5", work / "a.h5", None)
    _ok(_invoke("plot", a, results / "w25.h5", "--figure", "fig.yaml", "-o", "f.png"))
    check_png(work / "f.png")
    (work / "bad.yaml").write_text("figure:\n  kind: lissajous\n")
    check_error(_invoke("plot", a, "--figure", "bad.yaml", "-o", "g.png"), "figure.kind", "bad.yaml")
    (work / "none.yaml").write_text("title: x\n")
    check_error(_invoke("plot", a, "--figure", "none.yaml"), "no figure: section")
    assert not (work / "g.png").exists() and not (work / "a.png").exists()


def test_history_that_kept_only_z2(work, results):
    # Default channels come from the stored ones; the figure and the standard plots work.
    a = with_figure(results, "z2only.h5", work / "k.h5", "  kind: waveform\n")
    _ok(_invoke("plot", a, "-o", "k.png"))
    check_png(work / "k.png")
    a = with_figure(results, "z2only.h5", work / "k.h5", "  kind: waveform_fft\n")
    _ok(_invoke("plot", a, "-o", "kf.png"))
    check_png(work / "kf.png")
    std = with_figure(results, "z2only.h5", work / "std.h5", None)
    out = _ok(_invoke("plot", std))
    names = sorted(p.name for p in work.glob("std-*.png"))
    assert names == sorted(f"std-{s}.png" for s in HISTORY_SUFFIXES if s != "lissajous")  # one channel
    assert all(n in out for n in names)
    # Asking for a channel that was not stored: a clear error naming the stored one.
    bad = with_figure(results, "z2only.h5", work / "bad.h5", "  kind: waveform\n  channels: [z4]\n")
    flat = check_error(_invoke("plot", bad, "-o", "bad.png"), "z4", "z2", "outputs.channels")
    assert "kept only z2" in flat
    assert not (work / "bad.png").exists()
    with pytest.raises(CablesimError, match="kept only z2"):
        plot_history(read_history(results / "z2only.h5"), work / "p", "t", channels=["z4"])
    with pytest.raises(CablesimError, match="kept only z2"):
        plot_history(read_history(results / "z2only.h5"), work / "p", "t", pair=("z2", "z4"))


def test_split_needs_the_split_parts(work, results):
    a = with_figure(results, "z2only.h5", work / "ns.h5", "  kind: split\n")
    check_error(_invoke("plot", a), "outputs.split: true")
    assert not list(work.glob("*.png"))


# --------------------------------------------------------------------------------------------
# Standard plots (no figure section)
# --------------------------------------------------------------------------------------------


def test_standard_history_plots(work, results):
    a = with_figure(results, "full.h5", work / "h.h5", None)
    paths = redraw([a])
    assert [p.name for p in paths] == [f"h-{s}.png" for s in HISTORY_SUFFIXES]
    for p in paths:
        check_png(p, 5_000)
    out = _ok(_invoke("plot", a, "-o", "other.png"))  # -o: the prefix
    assert "other-fft.png" in out and (work / "other-waveforms.png").is_file()


def test_standard_sweep_plot_uses_plot_sweep(work, results, monkeypatch):
    import cablesim.plots.redraw as ps

    calls = []
    real = ps.plot_sweep

    def spy(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)

    monkeypatch.setattr(ps, "plot_sweep", spy)
    a = with_figure(results, "sweep.h5", work / "sw.h5", None)
    out = _ok(_invoke("plot", a))
    assert "sw.png" in out and len(calls) == 1
    check_png(work / "sw.png")


def test_standard_static_plot(work, results):
    # A figure section does not apply to a static file: its cable plot is drawn.
    a = with_figure(results, "static.h5", work / "st.h5", "  kind: waveform\n")
    out = _ok(_invoke("plot", a, "-o", "cable.png"))
    assert "cable.png" in out
    check_png(work / "cable.png")


@pytest.fixture
def saved_axes(monkeypatch):
    """Per figure as it is saved: (title, ylim, number of insets) of each axes."""
    from matplotlib.figure import Figure

    seen = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        seen.append([(ax.get_title(), ax.get_ylim(), len(ax.child_axes)) for ax in self.axes])
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    return seen


def test_every_figure_is_journal_width_with_readable_text(work, results, monkeypatch):
    """Standard and composite figures: 7 in wide, no visible text under 8 pt, no plain-text
    symbol (omega, a literal underscore) in any label."""
    from matplotlib.figure import Figure
    from matplotlib.text import Text

    seen = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        texts = [t for t in self.findobj(Text) if t.get_visible() and t.get_text().strip()]
        seen.append((self.get_figwidth(), min(t.get_fontsize() for t in texts), [t.get_text() for t in texts]))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    redraw([with_figure(results, "full.h5", work / "h.h5", None)])
    redraw([with_figure(results, "sweep.h5", work / "s.h5", None)])
    redraw([with_figure(results, "static.h5", work / "st.h5", None)])
    for kind, figure in KINDS.items():
        redraw([with_figure(results, "full.h5", work / f"{kind}.h5", figure),
                with_figure(results, "w25.h5", work / f"{kind}-b.h5", None)])
    redraw([with_figure(results, "full.h5", work / "snap.h5", None)], snapshots=4)
    assert len(seen) == 5 + 1 + 2 + len(KINDS) + 1  # static: the cable and its mode shapes
    for width, smallest, texts in seen:
        assert width == 7.0 and smallest >= 8.0
        outside_math = [re.sub(r"\$[^$]*\$", "", t) for t in texts]
        plain = [t for t in outside_math if re.search(r"\bomega\b|\bw = |_", t)]
        assert not plain, plain


def test_compared_panels_share_their_scales(work, results, saved_axes):
    """Two runs side by side: each panel role (Lissajous figure, tension changes) has the same
    limits in both columns, so that the sizes compare at a glance."""
    a = with_figure(results, "full.h5", work / "a.h5", KINDS["lissajous_tension"])
    b = with_figure(results, "w25.h5", work / "b.h5", None)
    _ok(_invoke("plot", a, b, "-o", "lt.png"))
    (axes,) = saved_axes
    tension = [ylim for title, ylim, _ in axes if title.startswith("segment tension")]
    lissajous = [ylim for title, ylim, _ in axes if title.startswith("Lissajous")]
    assert len(tension) == 2 and tension[0] == tension[1]
    assert len(lissajous) == 2 and lissajous[0] == lissajous[1]


def test_a_decaying_free_vibration_gets_an_inset(work, results, saved_axes):
    a = with_figure(results, "fv.h5", work / "fv.h5", "  kind: waveform\n  channels: [z2]\n")
    _ok(_invoke("plot", a, "-o", "fv.png"))
    (axes,) = saved_axes
    assert sum(n for _, _, n in axes) == 1


# --------------------------------------------------------------------------------------------
# Provenance and the preview stamp
# --------------------------------------------------------------------------------------------


@pytest.fixture
def saved_texts(monkeypatch):
    """The texts of every figure as it is saved."""
    from matplotlib.figure import Figure

    seen = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        seen.append([t.get_text() for t in self.texts])
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    return seen


def test_plot_stamp_is_drawn_and_the_png_records_how_it_was_made(work, results, saved_texts):
    from test_plot_style import png_text_chunks

    from cablesim.io.provenance import git_commit
    from cablesim.version import __version__

    a = with_figure(results, "sweep.h5", work / "sw.h5", "  kind: fdr\n")
    _ok(_invoke("plot", a, "-o", "preview.png", "--stamp", "preview: coarse grid"))
    assert len(saved_texts) == 1 and saved_texts[0].count("preview: coarse grid") == 1
    chunks = png_text_chunks(work / "preview.png")
    assert chunks["cablesim version"] == __version__
    assert chunks["git commit"] == (git_commit() or "unknown (not a git checkout)")
    assert chunks["Command"] == f"cablesim plot {a} --output preview.png --stamp 'preview: coarse grid'"
    assert chunks["Stamp"] == "preview: coarse grid"
    _ok(_invoke("plot", a, "-o", "plain.png"))
    assert "preview: coarse grid" not in saved_texts[-1] and "Stamp" not in png_text_chunks(work / "plain.png")


def test_the_api_stamps_the_standard_plots_too(work, results, saved_texts):
    import cablesim

    a = with_figure(results, "full.h5", work / "h.h5", None)
    paths = cablesim.plot([a], stamp="preview")
    assert len(paths) == len(HISTORY_SUFFIXES)
    assert all("preview" in texts for texts in saved_texts)


# --------------------------------------------------------------------------------------------
# Bad input: one paragraph, exit status 2, nothing written
# --------------------------------------------------------------------------------------------


def _not_hdf5(work, results):
    (work / "x.h5").write_text("not hdf5\n")
    return ["x.h5"], ("not an HDF5 file",)


def _foreign_hdf5(work, results):
    with h5py.File(work / "x.h5", "w") as f:
        f["data"] = np.arange(3)
    return ["x.h5"], ("not a cablesim result",)


def _mixed(work, results):
    return [results / "full.h5", results / "sweep.h5"], ("mix types", "sweep file", "time-history file")


def _two_files_one_output(work, results):
    a = with_figure(results, "full.h5", work / "a.h5", None)
    return [a, results / "w25.h5", "-o", "x.png"], ("-o names one output",)


def _labels(work, results):
    a = with_figure(results, "full.h5", work / "a.h5", "  kind: waveform\n  labels: [one]\n")
    return [a, results / "w25.h5"], ("figure.labels", "2 result file(s)")


def _fdr_on_history(work, results):
    a = with_figure(results, "full.h5", work / "a.h5", "  kind: fdr\n")
    return [a], ("fdr", "sweep files", "time-history file")


def _waveform_on_sweep(work, results):
    a = with_figure(results, "sweep.h5", work / "a.h5", "  kind: waveform\n")
    return [a], ("waveform", "sweep file")


def _window(work, results):
    a = with_figure(results, "full.h5", work / "a.h5", "  kind: waveform\n  time_window: [20, 10]\n")
    return [a], ("time_window", "increasing")


def _segments(work, results):
    a = with_figure(results, "full.h5", work / "a.h5", "  kind: lissajous_tension\n  segments: [4]\n")
    return [a], ("figure.segments", "segments 1 to 3")


def _bad_stored_case(work, results):
    a = with_figure(results, "full.h5", work / "a.h5", "  kind: pie\n")
    return [a], ("kind",)


BAD = {
    "missing": lambda w, r: (["nope.h5"], ("nope.h5", "does not exist")),
    "not-hdf5": _not_hdf5,
    "foreign-hdf5": _foreign_hdf5,
    "mixed": _mixed,
    "two-files-one-output": _two_files_one_output,
    "labels": _labels,
    "fdr-on-history": _fdr_on_history,
    "waveform-on-sweep": _waveform_on_sweep,
    "window": _window,
    "segments": _segments,
    "bad-stored-case": _bad_stored_case,
}


@pytest.mark.parametrize("make", list(BAD.values()), ids=list(BAD))
def test_bad_input_exit_2(work, results, make):
    args, words = make(work, results)
    check_error(_invoke("plot", *args), *words)
    assert not list(work.glob("*.png"))


def test_plot_needs_a_file(work):
    code, out, err, exc = _invoke("plot")
    assert code == 2 and "Missing argument" in err


def test_window_beyond_the_run_moves_to_its_end(work, results):
    """A window past the end of a (shorter, or stopped) run shows the same length at its end."""
    a = with_figure(results, "full.h5", work / "late.h5", "  kind: waveform\n  time_window: [100, 110]\n")
    from cablesim.plots.redraw import redraw

    (png,) = redraw([a], work / "late.png")
    check_png(png)
