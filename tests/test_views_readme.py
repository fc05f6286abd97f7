"""The README's block on mode shapes, animations and run reports runs as written (in-process),
and what it prints is what it wrote."""

from __future__ import annotations

import shlex
from pathlib import Path

import h5py
from PIL import Image
from typer.testing import CliRunner

from cablesim.case import example_text
from cablesim.cli import app

REPO = Path(__file__).resolve().parents[1]


def _block() -> list[str]:
    text = (REPO / "README.md").read_text()
    block = text.split("\n## Looking at results", 1)[1].split("```sh\n", 1)[1].split("```", 1)[0]
    return [line for line in block.splitlines() if line.strip()]


def test_the_readmes_results_block_runs_as_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    lines = _block()
    assert lines[0].startswith(".venv/bin/cablesim example > my-case.yaml")
    (tmp_path / "my-case.yaml").write_text(example_text())
    out = {}
    for line in lines[1:]:
        words = shlex.split(line, comments=True)
        assert words[0] == ".venv/bin/cablesim", line
        res = CliRunner().invoke(app, words[1:])
        assert res.exit_code == 0, (line, res.stdout[-1500:], res.stderr[-1500:], res.exception)
        out[words[1]] = res.stdout
    folder = tmp_path / "runs" / "my-case"
    assert (folder / "static-modes.png").is_file()
    gif = folder / "history-w2.4-d60-animation.gif"
    with Image.open(gif) as im:
        assert im.n_frames == 40
    readme = " ".join((REPO / "README.md").read_text().split())
    printed = out["animate"].split(": ", 1)[1].strip()
    assert " ".join(printed.split()) in readme  # the README quotes what the command prints
    with h5py.File(folder / "history-w2.4-d60.h5", "r") as f:
        assert f["history"].attrs["completed"]
    assert (folder / "static-report.html").stat().st_size > 100_000
