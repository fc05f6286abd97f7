"""Checks shared by the command-line hardening tests (refused input, files left behind)."""

from __future__ import annotations

from pathlib import Path

EXAMPLE = (Path(__file__).resolve().parents[1] / "cablesim" / "data" / "paper-example.yaml").read_text()

#: A one-node cable whose continuation over 2-3 rad/s takes about half a second.
ONE_NODE = """\
name: one
cable: {L: 10.0, H: 0.0, S: [5.2, 5.2], EA: 1.0e6, masses: [100.0]}
loads: {F0: [0.0, 2000.0], FL: [0.0, 100.0]}
damping: {ratio: 0.02, modes: [1, 2]}
history: {omega: 3.0, duration: 5.0, channels: [z2]}
continuation: {omega: {start: 2.0, stop: 3.0}, channels: [z1, z2]}
sweep: {omega: [2.2, 2.8], duration: 60.0, window: 20.0, channels: [z1, z2]}
"""


def flat(text: str) -> str:
    """A wrapped paragraph on one line."""
    return " ".join(text.split())


def error_paragraph(err: str) -> str:
    """Standard error without the notice that kernels are compiling on first use (printed, on a
    cold cache, before a refusal that the statics find)."""
    notices = ("compiling the numerical kernels", "compiling ", "compiled ")
    return "\n".join(line for line in err.strip().splitlines() if not line.startswith(notices))


def result_like_files(root: Path) -> list[Path]:
    """Every file a run could have left: results, plots, temporaries, journals and locks."""
    keep = (".h5", ".png", ".md", ".journal", ".lock")
    return sorted(p for p in root.rglob("*") if p.is_file() and (p.suffix in keep or ".part" in p.name))


def assert_refused(res, root: Path, *needles: str, keep: tuple[Path, ...] = ()) -> str:
    """Exit status 2, one paragraph on stderr naming the problem, no traceback, no file left.

    ``keep`` lists files that existed before the run (they must still be there); anything else
    result-like under ``root`` fails the check.
    """
    rc, out, err = res[0], res[1], res[2]
    assert rc == 2, f"exit status {rc}; stdout:\n{out}\nstderr:\n{err}\nexception: {res[3] if len(res) > 3 else ''!r}"
    if len(res) > 3:
        assert isinstance(res[3], SystemExit), repr(res[3])
    assert "Traceback" not in err and "Traceback" not in out
    msg = error_paragraph(err)
    assert msg.startswith("error: "), err
    assert "\n\n" not in msg and all(line.strip() for line in msg.splitlines()), "one paragraph"
    for needle in needles:
        assert needle in flat(msg), f"{needle!r} not in: {flat(msg)}"
    left = [p for p in result_like_files(root) if p not in keep]
    assert left == [], f"files left behind: {left}"
    for p in keep:
        assert p.exists(), f"{p} was removed"
    return flat(msg)


def example_with(*replacements: tuple[str, str]) -> str:
    """The example case text with each (old, new) replaced (old must occur)."""
    text = EXAMPLE
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new)
    return text
