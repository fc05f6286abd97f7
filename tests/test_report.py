"""`cablesim report` and `cablesim.report`: one self-contained HTML page whose tables hold the
numbers of the result files (read back here with h5py), with every figure of each run embedded,
and which a real browser (headless Chromium, where installed) renders with every figure."""

from __future__ import annotations

import base64
import math
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

import cablesim
from cablesim.cli import app
from helpers_cli import assert_refused

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


def cli(*args):
    res = CliRunner().invoke(app, [str(a) for a in args])
    assert res.exit_code == 0, (args, res.stdout[-2000:], res.stderr[-2000:], res.exception)
    return res


class Page(HTMLParser):
    """The tables of a page (by id: rows of (text, data-value)), its images and its links."""

    def __init__(self, text: str):
        super().__init__()
        self.tables: dict[str, list[list[tuple[str, float | None]]]] = {}
        self.images: list[str] = []
        self.urls: list[str] = []
        self._table = self._cell = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table" and "id" in a:
            self._table = self.tables.setdefault(a["id"], [])
        elif tag == "tr" and self._table is not None:
            self._table.append([])
        elif tag == "td" and self._table is not None:
            v = a.get("data-value")
            self._cell = ["", None if v is None else float(v)]
        elif tag == "img":
            self.images.append(a["src"])
        for k in ("src", "href"):
            if k in a and not a[k].startswith(("data:", "#")):
                self.urls.append(a[k])

    def handle_data(self, data):
        if self._cell is not None:
            self._cell[0] += data

    def handle_endtag(self, tag):
        if tag == "td" and self._cell is not None:
            self._table[-1].append(tuple(self._cell))
            self._cell = None
        elif tag == "table":
            self._table = None

    def column(self, table: str, k: int) -> np.ndarray:
        return np.array([row[k][1] for row in self.tables[table] if row], dtype=float)

    def texts(self, table: str, k: int) -> list[str]:
        return [row[k][0] for row in self.tables[table] if row]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A static run, a short history, a two-point sweep and a short continuation, with their
    figures beside them (a second history without figures); their report."""
    root = tmp_path_factory.mktemp("report")
    cli("static", "-o", root / "static.h5")
    cli("history", "--duration", "12", "-o", root / "hist.h5")
    cli("history", "--duration", "6", "-o", root / "bare.h5", "--no-plot")
    cli("sweep", "--omega", "2.3,2.5", "--duration", "200", "--window", "40", "--jobs", "1",
        "--set", "sweep.refine=false", "-o", root / "sweep.h5")
    cli("continue", "--set", "continuation.omega={start: 5.0, stop: 5.06}", "-o", root / "cont.h5")
    files = [root / n for n in ("static.h5", "hist.h5", "sweep.h5", "cont.h5", "bare.h5")]
    res = cli("report", *files, "-o", root / "report.html")
    return root, files, res


@pytest.fixture(scope="module")
def page(runs):
    return Page((runs[0] / "report.html").read_text())


def read(path, *names):
    with h5py.File(path, "r") as f:
        return [f[n][()] for n in names]


def test_static_tables_hold_the_files_numbers(runs, page):
    root = runs[0]
    T, P, omega, xi = read(root / "static.h5", "static/exact/T", "static/P", "modal/omega", "modal/damping_ratio")
    np.testing.assert_allclose(page.column("f1-tensions", 1) * 1e3, T, rtol=1e-12)
    # reactions: each end tension's size, and together they carry the loads (an independent balance)
    h, v, mag = (page.column("f1-reactions", k) * 1e3 for k in (1, 2, 3))
    np.testing.assert_allclose(mag, [T[0], T[-1]], rtol=1e-12)
    np.testing.assert_allclose([h.sum(), v.sum()], P.reshape(-1, 2).sum(axis=0), rtol=1e-9)
    np.testing.assert_allclose(page.column("f1-modes", 1), omega, rtol=1e-12)
    np.testing.assert_allclose(page.column("f1-modes", 2), omega / (2 * math.pi), rtol=1e-12)
    np.testing.assert_allclose(page.column("f1-modes", 4), xi, rtol=1e-12)


def test_history_tables_hold_the_files_numbers(runs, page):
    root = runs[0]
    z, peak, T0 = read(root / "hist.h5", "history/z", "history/segments/peak_tension", "history/T0")
    np.testing.assert_allclose(page.column("f2-displacements", 4), np.abs(z).max(axis=0), rtol=1e-12)
    np.testing.assert_allclose(page.column("f2-displacements", 2), z.min(axis=0), rtol=1e-12)
    np.testing.assert_allclose(page.column("f2-history-tensions", 3) * 1e3, peak, rtol=1e-12)
    np.testing.assert_allclose(page.column("f2-history-tensions", 1) * 1e3, T0, rtol=1e-12)


def test_sweep_peaks_and_bifurcations_hold_the_files_numbers(runs, page):
    root = runs[0]
    w, amp, steady = read(root / "sweep.h5", "sweep/omega", "sweep/amplitude", "sweep/steady")
    k = np.argmax(amp, axis=0)  # per channel, independently of the report's code
    np.testing.assert_allclose(page.column("f3-sweep-peaks", 3), amp[k, range(amp.shape[1])], rtol=1e-12)
    np.testing.assert_allclose(page.column("f3-sweep-peaks", 2), w[k], rtol=1e-12)
    np.testing.assert_allclose(page.column("f3-sweep-points-1", 0), w, rtol=1e-12)
    kinds, bw = read(root / "cont.h5", "continuation/bifurcations/kind", "continuation/bifurcations/omega")
    assert page.texts("f4-bifurcations", 0) == [k.decode() for k in kinds]
    np.testing.assert_allclose(page.column("f4-bifurcations", 1), bw, rtol=1e-12)
    with h5py.File(root / "cont.h5", "r") as f:
        assert page.texts("f4-branches", 0) == sorted(f["continuation/branches"], key=lambda b: int(
            f["continuation/branches"][b].attrs["index"]))
    unsteady = int((~steady).sum())
    text = (root / "report.html").read_text()
    assert (f"{unsteady} point(s) not steady" in text) == (unsteady > 0)


def test_provenance_is_the_files(runs, page):
    root, files, _ = runs
    for k, path in enumerate(files, start=1):
        with h5py.File(path, "r") as f:
            want = {a: str(f.attrs[a]) for a in ("command_line", "git_commit", "numpy_version", "h5py_version")}
        got = {row[0][0]: row[1][0] for row in page.tables[f"f{k}-provenance"] if row}
        assert got["command line"] == want["command_line"]
        assert got["git commit"] == want["git_commit"]
        assert got["numpy"] == want["numpy_version"] and got["h5py"] == want["h5py_version"]


def test_every_figure_is_embedded_and_nothing_is_fetched(runs, page):
    root = runs[0]
    beside = sorted(p.name for p in root.glob("*.png"))
    assert len(beside) >= 2 + 5 + 1 + 1  # static (with modes), history, sweep, continuation
    # every PNG beside the files, and the bare history's five drawn for the page
    assert len(page.images) == len(beside) + 5
    for src in page.images:
        head, data = src.split(",", 1)
        assert head == "data:image/png;base64"
        assert base64.b64decode(data)[:8] == PNG_MAGIC
    assert page.urls == []
    text = (root / "report.html").read_text()
    assert "<link" not in text and "@import" not in text and "http" not in text.split("<body", 1)[1].split("<pre>")[0]
    assert "drawn for this report" in text  # the bare history says its figures were drawn for the page
    assert runs[2].stdout.startswith(f"Wrote {root / 'report.html'}")


def test_bad_input_is_refused(invoke_cli, runs, tmp_path):
    root = runs[0]
    assert_refused(invoke_cli("report", root / "static.h5", "-o", "r.txt"), tmp_path, "-o r.txt", ".html")
    assert_refused(invoke_cli("report", "missing.h5"), tmp_path, "missing.h5", "does not exist")
    (tmp_path / "other.h5").write_bytes(b"not hdf5")
    assert_refused(invoke_cli("report", "other.h5", "-o", "r.html"), tmp_path, "not an HDF5 file",
                   keep=(tmp_path / "other.h5",))


def test_the_api_writes_the_same_tables(runs, tmp_path):
    root = runs[0]
    out = cablesim.report([root / "static.h5"], tmp_path / "s.html")
    p = Page(out.read_text())
    assert set(p.tables) >= {"f1-tensions", "f1-reactions", "f1-modes", "f1-provenance", "f1-case"}
    T, = read(root / "static.h5", "static/exact/T")
    np.testing.assert_allclose(p.column("f1-tensions", 1) * 1e3, T, rtol=1e-12)


def _chromium(*args, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                           f"--user-data-dir={cwd / 'chromium-profile'}", *args],
                          cwd=cwd, capture_output=True, text=True, timeout=120)


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium)")
def test_a_headless_browser_renders_the_page_with_every_figure(runs, tmp_path):
    from PIL import Image

    html_path = runs[0] / "report.html"
    url = html_path.resolve().as_uri()
    dom = _chromium("--virtual-time-budget=10000", "--dump-dom", url, cwd=tmp_path).stdout
    total = int(re.search(r'data-figures="(\d+)"', dom).group(1))
    loaded = int(re.search(r'data-figures-loaded="(\d+)"', dom).group(1))
    assert total == len(Page(html_path.read_text()).images) and loaded == total
    shot = tmp_path / "shot.png"
    _chromium("--window-size=900,4000", f"--screenshot={shot}", url, cwd=tmp_path)
    with Image.open(shot) as im:
        pixels = np.asarray(im.convert("L"), dtype=float)
    assert pixels.shape == (4000, 900)
    dark = (pixels < 200).mean()
    assert 0.01 < dark < 0.6, dark  # text, tables and figures drawn: not a blank page
    assert pixels.std() > 20
    # a phone's width: the page reflows (nothing wider than the screen but the scrolling tables)
    phone = tmp_path / "phone.png"
    _chromium("--window-size=390,2000", f"--screenshot={phone}", url, cwd=tmp_path)
    with Image.open(phone) as im:
        assert (np.asarray(im.convert("L"), dtype=float) < 200).mean() > 0.01
    # in print: each result file starts a page
    pdf = tmp_path / "report.pdf"
    _chromium("--no-pdf-header-footer", f"--print-to-pdf={pdf}", url, cwd=tmp_path)
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF") and len(re.findall(rb"/Type\s*/Page[^s]", data)) >= len(runs[1])


def test_a_static_strain_warning_is_in_the_report(tmp_path):
    case = cablesim.load_case(None, ["cable.E=8.0e9"])  # EA = 4e7 N: the paper's loads stretch it beyond 5 %
    run = cablesim.static(case)
    assert run.result.warnings
    page = cablesim.report([run.to_hdf5(tmp_path / "s.h5")], tmp_path / "s.html").read_text()
    warnings = page.split('id="f1-warnings"', 1)[1].split("</div>", 1)[0]
    assert "static strain T/EA of segment" in warnings
