"""No text of a standard figure overlaps other text or leaves the figure, and no label of a point
lies outside its axes (read from matplotlib's own layout: ``helpers_figures.text_problems``).

Every standard figure of the shipped examples (``cablesim example``: the paper's example and the
heavy span) and of the paper scenes (``configs/paper``) is drawn from short runs and coarse
grids: static, the five time-history figures (a slack run's tensions too), snapshots, sweeps
with and without gamma curves and up/down chains, continuation with a sweep drawn over it, and
each scene's own figure (``figure:`` sections and ``*.figure.yaml`` files).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from cablesim.case import example_text
from cablesim.cli import app
from helpers_figures import text_problems, watch_figures

REPO = Path(__file__).resolve().parents[1]
SCENES = REPO / "configs" / "paper"
SHORT_SWEEP = ["--duration", "200", "--window", "40", "--jobs", "1", "--set", "sweep.refine=false"]


def _run(*args) -> None:
    res = CliRunner().invoke(app, [str(a) for a in args])
    assert res.exit_code in (0, 3), (args, res.stdout[-2000:], res.stderr[-2000:], res.exception)


def _grid(scene: Path, count: int = 3) -> str:
    """``count`` frequencies inside a scene's sweep range."""
    text = scene.read_text()
    m = re.search(r"omega: \{start: ([\d.]+), stop: ([\d.]+)", text.split("\nsweep:")[1])
    lo, hi = float(m.group(1)), float(m.group(2))
    return ",".join(f"{lo + (hi - lo) * (k + 0.5) / count:.4g}" for k in range(count))


def _examples(root: Path) -> None:
    (root / "my-case.yaml").write_text(example_text())
    (root / "heavy.yaml").write_text(example_text("heavy-span"))
    _run("static", "my-case.yaml")
    _run("history", "my-case.yaml", "--duration", "60")
    _run("free-vibration", "my-case.yaml")
    _run("sweep", "my-case.yaml", "--omega", "2.3,2.48,2.6", *SHORT_SWEEP)
    _run("sweep", "my-case.yaml", "--omega", "2.3,2.48,2.6", *SHORT_SWEEP, "--set", "sweep.gamma=[0.5, 1.0]",
         "--set", "sweep.direction=both", "-o", "gammas.h5")
    _run("continue", "my-case.yaml", "--set", "continuation.omega={start: 4.95, stop: 5.1}")
    _run("plot", "runs/my-case/continuation.h5", "runs/my-case/sweep-w2.3,2.48,2.6.h5", "-o", "overlay.png")
    _run("plot", "runs/my-case/history-w2.4-d60.h5", "--snapshots", "6", "-o", "snap.png")
    _run("history", "my-case.yaml", "--omega", "2.45", "--duration", "40", "-o", "slack.h5",
         "--set", "loads.FL=[-60.0e3, 220.0e3, -180.0e3, 1200.0e3]")
    _run("static", "heavy.yaml")
    _run("history", "heavy.yaml", "--duration", "8")
    _run("plot", "runs/heavy/history-w2.3-d8.h5", "--snapshots", "6", "-o", "heavy-snap.png")


def _scene_runs(root: Path) -> None:
    """Each scene run short (its command; a history of 10 s, a sweep of two points capped at
    100 s, a continuation of 20 orbits), and its own figure drawn (those without a ``figure:``
    section feed another's, or draw the standard figures the examples draw)."""
    short = {"free-vibration": ["--duration", "2"], "history": ["--duration", "10"]}
    for scene in sorted(SCENES.glob("*.yaml")):
        if scene.name.endswith(".figure.yaml"):
            continue
        text = scene.read_text()
        out = root / f"{scene.stem}.h5"
        if "\nsweep:" in text and "\n  omega: {start" in text.split("\nsweep:")[1][:80]:
            _run("sweep", scene, "--omega", _grid(scene, 2), *SHORT_SWEEP, "--duration", "100", "--no-plot", "-o", out)
            if "\ncontinuation:" in text:
                rng = text.split("\ncontinuation:")[1]
                lo = float(re.search(r"omega: \{start: ([\d.]+)", rng).group(1))
                _run("continue", scene, "-o", root / f"{scene.stem}-continuation.h5", "--no-plot",
                     "--set", f"continuation.omega={{start: {lo}, stop: {lo * 1.05:.4g}}}",
                     "--set", "continuation.max_points=20", "--set", "continuation.switch_branches=false")
                _run("plot", root / f"{scene.stem}-continuation.h5", out, "-o", root / f"{scene.stem}-continuation.png")
        else:
            command = "free-vibration" if "\nfree_vibration:" in text else "history"
            _run(command, scene, *short[command], "--no-plot", "-o", out)
        if "\nfigure:" in text:
            _run("plot", out, "-o", root / f"{scene.stem}.png")
    for figure, files in (("fig6-7a", ("fig6", "fig7a")), ("fig7b", ("fig7-mode1", "fig7-mode2")),
                          ("fig7c", ("fig7-mode1", "fig7-mode2"))):
        _run("plot", *(root / f"{f}.h5" for f in files), "--figure", SCENES / f"{figure}.figure.yaml",
             "-o", root / f"{figure}.png")


def _drawn(tmp_path_factory, runs):
    root = tmp_path_factory.mktemp("figures")
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(root)
        with watch_figures(mp) as seen:
            runs(root)
    return seen


@pytest.fixture(scope="module")
def examples(tmp_path_factory):
    """Every standard figure of the shipped examples, with the text problems of each (by PNG)."""
    return _drawn(tmp_path_factory, _examples)


def _problems(drawn) -> str:
    return "\n".join(f"{name}: {p}" for name, problems in drawn.items() for p in problems)


def test_every_standard_figure_was_drawn(examples):
    names = set(examples)
    for kind in ("waveforms", "phase", "lissajous", "tensions", "fft"):
        assert any(n.endswith(f"-{kind}.png") for n in names), kind
    for name in ("static.png", "overlay.png", "snap.png", "heavy-snap.png", "gammas.png", "continuation.png"):
        assert name in names, (name, sorted(names))


def test_no_text_overlaps_other_text_or_leaves_the_figure(examples):
    """The static figure dropped its largest load arrow and printed labels over each other; the
    two-line y labels of stacked panels overlapped; phase-plot tick labels collided; a PD label
    lay under its axis; a long title ran past the figure's edges."""
    assert not _problems(examples), _problems(examples)


@pytest.mark.slow
def test_no_text_overlaps_in_the_paper_scenes(tmp_path_factory):
    drawn = _drawn(tmp_path_factory, _scene_runs)
    for name in ("fig2.png", "fig3a.png", "fig3a-continuation.png", "fig3b.png", "fig4.png", "fig5a.png",
                 "fig5b.png", "fig6-7a.png", "fig7b.png", "fig7c.png", "fig8a.png", "fig8b.png", "fig8c.png"):
        assert name in drawn, (name, sorted(drawn))
    assert not _problems(drawn), _problems(drawn)


def test_the_checker_finds_an_overlap_and_a_dropped_annotation():
    """The check itself sees what it is for (two texts on one spot; an annotation whose point
    lies outside the axes, which matplotlib then does not draw)."""
    from cablesim.plots.base import pyplot

    fig, ax = pyplot().subplots(layout="constrained")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.text(0.5, 0.5, "first label")
    ax.text(0.52, 0.5, "second label")
    ax.annotate("outside", (2.0, 0.5))
    problems = text_problems(fig)
    assert any("overlaps" in p and "first label" in p for p in problems)
    assert any("is not drawn" in p and "outside" in p for p in problems)
    pyplot().close(fig)
