"""Vector and journal figures: ``--format png|pdf|svg`` (or the output's suffix), ``--width``
(in) and ``--dpi`` on the commands that draw, fonts embedded in PDF.

The PDF is read here without a PDF library: its streams inflated with zlib, the strings of its
text operators (Tj, TJ) decoded (matplotlib writes TrueType text as two-byte character codes),
its page size from the MediaBox (1/72 in), the embedded fonts from their dictionaries.
"""

from __future__ import annotations

import re
import struct
import zlib

import pytest

from helpers_cli import assert_refused

_ESCAPES = {b"n": b"\n", b"r": b"\r", b"t": b"\t", b"b": b"\b", b"f": b"\f", b"(": b"(", b")": b")", b"\\": b"\\"}
_STRING = rb"\(((?:\\.|[^\\)])*)\)"


def _unescape(s: bytes) -> bytes:
    out, i = bytearray(), 0
    while i < len(s):
        if s[i:i + 1] == b"\\":
            octal = re.match(rb"[0-7]{1,3}", s[i + 1:i + 4])
            if octal:
                out.append(int(octal.group(), 8) & 0xFF)
                i += 1 + len(octal.group())
                continue
            out += _ESCAPES.get(s[i + 1:i + 2], s[i + 1:i + 2])
            i += 2
            continue
        out += s[i:i + 1]
        i += 1
    return bytes(out)


def pdf_texts(pdf: bytes) -> list[str]:
    """The text of every Tj and TJ operator of the PDF's content streams."""
    found = []
    for m in re.finditer(rb"stream\r?\n(.*?)\r?\nendstream", pdf, re.S):
        try:
            data = zlib.decompress(m.group(1))
        except zlib.error:
            continue  # an embedded font program or image
        for op in re.finditer(rb"\[((?:" + _STRING + rb"|[^\]])*)\]\s*TJ|" + _STRING + rb"\s*Tj", data, re.S):
            raw = b"".join(_unescape(p) for p in re.findall(_STRING, op.group(0)))
            found.append(raw.decode("utf-16-be") if len(raw) % 2 == 0 else raw.decode("latin-1"))
    return found


def png_size(path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_static_pdf_opens_embeds_its_fonts_and_holds_the_figures_text(invoke_cli, tmp_path):
    res = invoke_cli("static", "-o", "s.h5", "--format", "pdf", "--width", "3.5")
    assert res[0] == 0, res
    assert "Wrote s.h5 and s.pdf" in res[1] and not (tmp_path / "s.png").exists()
    pdf = (tmp_path / "s.pdf").read_bytes()
    assert pdf.startswith(b"%PDF-") and pdf.rstrip().endswith(b"%%EOF")
    assert b"/FontFile2" in pdf and b"/Type3" not in pdf  # TrueType embedded (pdf.fonttype 42), no Type 3
    texts = pdf_texts(pdf)
    assert "horizontal coordinate (m)" in texts and "vertical coordinate (m), pointing down" in texts
    assert any("paper-example: static equilibrium" in t for t in texts)
    width, height = (float(v) for v in re.search(rb"/MediaBox \[\s*0 0 ([\d.]+) ([\d.]+)", pdf).groups())
    assert width == pytest.approx(3.5 * 72)  # --width 3.5 in, in points
    assert b"cablesim static" in pdf  # the command, in the document information (Subject)


def test_history_svg_and_the_plot_commands_suffix(invoke_cli, tmp_path):
    assert invoke_cli("history", "--duration", "2", "-o", "h.h5", "--no-plot")[0] == 0
    res = invoke_cli("plot", "h.h5", "--format", "svg")
    assert res[0] == 0, res
    for kind in ("waveforms", "phase", "lissajous", "tensions", "fft"):
        svg = (tmp_path / f"h-{kind}.svg").read_text()
        assert svg.startswith("<?xml") and "<svg" in svg and "cablesim plot h.h5 --format svg" in svg
    assert not list(tmp_path.glob("h-*.png"))
    assert invoke_cli("static", "-o", "s.h5", "--no-plot")[0] == 0
    assert invoke_cli("plot", "s.h5", "-o", "cable.pdf")[0] == 0  # the format from the suffix
    assert (tmp_path / "cable.pdf").read_bytes().startswith(b"%PDF-")


def test_width_and_dpi_set_the_png_size(invoke_cli, tmp_path):
    assert invoke_cli("static", "-o", "narrow.h5", "--width", "3.5", "--dpi", "100")[0] == 0
    assert png_size(tmp_path / "narrow.png")[0] == 350  # 3.5 in at 100 dpi
    assert invoke_cli("static", "-o", "wide.h5", "--dpi", "50")[0] == 0
    assert png_size(tmp_path / "wide.png")[0] == 350  # the default 7 in at 50 dpi


@pytest.mark.parametrize("args, needles", [
    (["static", "--width", "1"], ["--width 1", "from 3 to 14"]),
    (["static", "--dpi", "5"], ["--dpi 5", "from 50 to 1200"]),
    (["static", "--format", "eps"], ["eps"]),
])
def test_bad_figure_options_are_refused(invoke_cli, tmp_path, args, needles):
    res = invoke_cli(*args, "-o", "x.h5")
    assert res[0] == 2 and "Traceback" not in res[2]
    assert all(n in " ".join(res[2].split()) for n in needles), res[2]
    assert not list(tmp_path.glob("x.*"))


def test_a_format_that_clashes_with_the_suffix_is_refused(invoke_cli, tmp_path):
    assert invoke_cli("static", "-o", "s.h5", "--no-plot")[0] == 0
    keep = (tmp_path / "s.h5",)
    assert_refused(invoke_cli("plot", "s.h5", "-o", "f.pdf", "--format", "svg"), tmp_path,
                   "--format svg and -o f.pdf name different formats", keep=keep)


def test_a_replaced_result_takes_its_figures_in_every_format_with_it(invoke_cli, tmp_path):
    assert invoke_cli("static", "-o", "s.h5", "--format", "svg")[0] == 0 and (tmp_path / "s.svg").is_file()
    assert invoke_cli("static", "-o", "s.h5")[0] == 0
    assert (tmp_path / "s.png").is_file() and not (tmp_path / "s.svg").exists()
