"""The paper-figure make targets, end to end, in their FAST form.

Runs ``make fig3b FAST=1`` (a waveform figure) and, in ``make test-all``, ``make fig3a
fig3a-continuation FAST=1`` (a frequency-response figure and its continuation over the
brute-force points) into temporary folders and checks the HDF5 results and the PNGs, and that
the FAST figures still show the phenomena they are named for (the late jump, the subharmonic
band); then that make does not rerun a scene whose case file, code and settings have not changed.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="needs make")


def make(out: Path, *targets: str) -> subprocess.CompletedProcess:
    cli = f"{sys.executable} -m cablesim.cli"
    return subprocess.run(
        ["make", "--no-print-directory", "-C", str(ROOT), *targets, "FAST=1", f"OUTD={out}", f"RUN={cli}"],
        capture_output=True, text=True, timeout=600,
    )


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper-fast")
    r = make(out, "fig3a", "fig3a-continuation")
    assert r.returncode == 0, r.stdout + r.stderr
    return out, r


@pytest.fixture(scope="module")
def built_waveform(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper-fast-waveform")
    r = make(out, "fig3b")
    assert r.returncode == 0, r.stdout + r.stderr
    return out, r


@pytest.mark.slow  # a sweep of 33 frequencies and its continuation: `make test` runs the waveform scene
def test_fdr_figure(built):
    out, _ = built
    png = out / "fig3a.png"
    assert png.read_bytes()[:8] == PNG_MAGIC and png.stat().st_size > 20_000
    with h5py.File(out / "fig3a.h5") as f:
        assert f.attrs["command"] == "sweep"
        w = f["sweep/omega"][()]
        amp = f["sweep/amplitude"][()]
        period = f["sweep/period"][()]
        assert f["sweep/done"][()].all()
        # the FAST grid the Makefile gave on the command line, not the full one
        grid = re.search(r"sweep\.omega=\[([^]]*)\]", built[1].stdout).group(1)
        assert np.allclose(np.sort(w), sorted(float(x) for x in grid.split(",")))
        assert w.size < 276
        # The fundamental resonance of the paper example (2.52 rad/s, softening) dominates z2.
        assert abs(w[np.argmax(amp[:, 0])] - 2.5) < 0.3
        # The FAST grid keeps the subharmonic band: period-2 responses near 2 w1 and only there.
        assert np.all((period >= 2) <= (np.abs(w - 5.05) < 0.05)) and (period >= 2).sum() >= 2
        assert "history" not in f  # an FDR scene stores amplitudes, not time histories


@pytest.mark.slow
def test_continuation_figure(built):
    out, _ = built
    png = out / "fig3a-continuation.png"
    assert png.read_bytes()[:8] == PNG_MAGIC and png.stat().st_size > 20_000
    with h5py.File(out / "fig3a-continuation.h5") as f:
        assert f.attrs["command"] == "continue"
        kinds = sorted(k.decode() for k in f["continuation/bifurcations/kind"][()])
        assert kinds.count("period-doubling") == 2  # the subharmonic band near 2 w1
        periods = sorted(int(b.attrs["period"]) for b in f["continuation/branches"].values())
        assert periods == [1, 2]


def test_waveform_figure(built_waveform):
    out, _ = built_waveform
    png = out / "fig3b.png"
    assert png.read_bytes()[:8] == PNG_MAGIC and png.stat().st_size > 20_000
    with h5py.File(out / "fig3b.h5") as f:
        assert f.attrs["command"] == "history"
        assert list(f["history/dof"][()]) == [2]  # the scene keeps only the channel it draws
        assert "zc" not in f["history"]  # and skips the configurational/elastic split
        t = f["history/t"][()]
        z = f["history/z"][()][:, 0]
        assert abs(t[-1] - 3000.0) < 1.0 and np.isfinite(z).all()
        # long enough for the late jump: the small response grows over ten times larger
        small = np.abs(z[(t > 400) & (t < 500)]).max()
        assert np.abs(z[t > 2900]).max() > 10 * small


def test_make_does_not_rerun_an_unchanged_scene(built_waveform):
    out, first = built_waveform
    assert "cablesim.cli history" in first.stdout  # the first make ran the scene
    before = (out / "fig3b.h5").stat().st_mtime_ns
    r = make(out, "fig3b")
    assert r.returncode == 0, r.stderr
    assert "cablesim.cli history" not in r.stdout and "cablesim.cli plot" not in r.stdout
    assert (out / "fig3b.h5").stat().st_mtime_ns == before
