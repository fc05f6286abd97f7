"""The reproduction document, its numbers and the make targets behind them.

- every number docs/paper-reproduction.md tags (``6.56<!--=fig4.peak.g0.06.z2-->``) is printed
  as docs/paper-numbers.json (written by ``make paper-numbers WRITE=1`` from the stored results)
  has it, and every number in the file is quoted;
- the FAST grids (read from what ``make -n FAST=1 figures`` would run) contain every grid
  frequency the document quotes, and the FAST histories of the late jumps outlast them;
- make reruns a scene when cablesim's code or the scene's settings change, and redraws a figure
  (only) when the plotting code changes.
"""

from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cablesim.api import load_case

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "paper-reproduction.md"
NUMBERS = ROOT / "docs" / "paper-numbers.json"
#: A quoted number and its key: the number (sign, digits, decimal point) right before the tag.
TAG = re.compile(r"((?:(?<![\w.>])[+-])?\d[\d.]*(?:e[+-]\d+)?|stable|unstable)\**<!--=([\w.+-]+)-->")

needs_make = pytest.mark.skipif(shutil.which("make") is None, reason="needs make")


def numbers() -> dict:
    return json.loads(NUMBERS.read_text())["numbers"]


def tags() -> list[tuple[str, str]]:
    text = DOC.read_text()
    found = TAG.findall(text)
    # A tag the pattern did not pair with a number would be skipped silently: count them all.
    assert len(found) == text.count("<!--="), "a tag <!--=key--> does not follow a number directly"
    return found


def test_every_tagged_number_is_the_computed_one():
    known = numbers()
    found = tags()
    assert len(found) > 100
    wrong = [f"{key}: document {text}, computed {known[key]['text']}" for text, key in found
             if key in known and known[key]["text"] != text]
    unknown = [key for _, key in found if key not in known]
    assert not unknown, f"tags without a computed number: {unknown}"
    assert not wrong, "\n".join(wrong)


def test_every_computed_number_is_quoted_with_its_resolution():
    quoted = {key for _, key in tags()}
    missing = [k for k in numbers() if k not in quoted]
    assert not missing, f"computed but not quoted: {missing}"
    for key, item in numbers().items():
        assert item["resolution"] and item["source"], key


def test_quoted_frequencies_are_printed_to_their_grid_step():
    # A frequency read off a grid has as many decimals as the grid step, no more.
    for key, item in numbers().items():
        if "grid" in item:
            step = numbers()[f"{item['grid']}.step"]["value"]
            decimals = len(item["text"].split(".")[1]) if "." in item["text"] else 0
            assert 10.0 ** -decimals <= step + 1e-12, (key, item["text"], step)
            assert abs(item["value"] - float(item["text"])) < 1e-9, key  # grid points print exactly


def dry_run(*args) -> str:
    """What make would run into an empty folder (nothing is run; the install stamp is this file)."""
    r = subprocess.run(["make", "--no-print-directory", "-n", "-C", str(ROOT), *args, "OUTD=/nonexistent/fast",
                        "RUN=CABLESIM", f"STAMP={Path(__file__).resolve()}"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return r.stdout


def fast_commands() -> dict[str, list[str]]:
    """Scene -> arguments of the cablesim command ``make FAST=1 figures`` runs for it."""
    stdout = dry_run("figures", "FAST=1")
    out = {}
    for line in stdout.splitlines():
        if line.startswith("CABLESIM ") and " -o " in line:
            args = shlex.split(line.split("||")[0])[1:]
            if args[0] in ("sweep", "history", "free-vibration"):  # not plot, not continue
                out[Path(args[args.index("-o") + 1]).stem] = args
    return out


def fast_case(args):
    overrides = [args[i + 1] for i, a in enumerate(args) if a == "--set"]
    return load_case(ROOT / args[1], overrides)


@needs_make
def test_fast_grids_contain_every_quoted_grid_frequency():
    cmds = fast_commands()
    grids = {}
    for scene, args in cmds.items():
        if args[0] == "sweep":
            grids[scene] = fast_case(args).sweep.frequencies()
    assert {"fig3a", "fig4", "fig5a", "fig6", "fig7a", "fig8a"} <= set(grids)
    quoted = [(k, v) for k, v in numbers().items() if "grid" in v]
    assert len(quoted) > 20
    missing = [f"{k} = {v['text']}" for k, v in quoted
               if not any(abs(w - v["value"]) < 1e-9 for w in grids[v["grid"]])]
    assert not missing, f"quoted grid frequencies missing from the FAST grids: {missing}"
    # FAST is coarse: fewer points than the full figures.
    full = {s: load_case(ROOT / "configs" / "paper" / f"{s}.yaml").sweep.frequencies().size for s in grids}
    assert all(grids[s].size < full[s] for s in grids)


@needs_make
def test_fast_histories_outlast_the_jumps():
    cmds = fast_commands()
    for scene in ("fig3b", "fig8c"):
        duration = fast_case(cmds[scene]).history.duration
        jump = numbers()[f"{scene}.jump"]["value"]
        # the jump (half the final amplitude) and as long again to settle
        assert duration >= 1.5 * jump, (scene, duration, jump)


@needs_make
def test_fast_figures_are_stamped_as_previews():
    stdout = dry_run("fig3a", "fig7b", "fig3a-continuation", "FAST=1")
    plots = [line for line in stdout.splitlines() if line.startswith("CABLESIM plot")]
    assert len(plots) == 3 and all('--stamp "preview: coarse grid, short runs"' in p for p in plots), stdout


FAKE_CLI = """\
import sys
from pathlib import Path
args = sys.argv[1:]
out = Path(args[args.index("-o") + 1])
out.parent.mkdir(parents=True, exist_ok=True)
out.write_text(" ".join(args))
with open(sys.argv[0] + ".log", "a") as f:
    f.write(" ".join(args) + "\\n")
"""


@needs_make
def test_make_reruns_a_scene_when_the_code_or_its_settings_change(tmp_path):
    fake = tmp_path / "cli.py"
    fake.write_text(FAKE_CLI)
    sim, plot = tmp_path / "sim.py", tmp_path / "plot.py"
    sim.write_text("a = 1\n")
    plot.write_text("b = 1\n")
    (tmp_path / ".installed").touch()
    out = tmp_path / "out"

    def run(*extra):
        before = fake.with_suffix(".py.log").read_text().splitlines() if fake.with_suffix(".py.log").exists() else []
        r = subprocess.run(["make", "--no-print-directory", "-C", str(ROOT), f"{out}/fig3a.png", "FAST=1",
                            f"OUTD={out}", f"RUN={sys.executable} {fake}", f"STAMP={tmp_path}/.installed",
                            f"SIM_SRC={sim}", f"PLOT_SRC={plot}", *extra],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stdout + r.stderr
        after = fake.with_suffix(".py.log").read_text().splitlines()
        return [line.split()[0] for line in after[len(before):]]

    assert run() == ["sweep", "plot"]
    assert run() == []  # nothing changed
    sim.write_text("a = 2\n")
    assert run() == ["sweep", "plot"]  # the code changed
    assert run() == []
    assert run("ARGS_fig3a=--set sweep.duration=100") == ["sweep", "plot"]  # the FAST settings changed
    assert run("ARGS_fig3a=--set sweep.duration=100") == []
    plot.write_text("b = 2\n")
    assert run("ARGS_fig3a=--set sweep.duration=100") == ["plot"]  # only the drawing changed


def paper_numbers_module():
    import importlib.util

    spec = importlib.util.spec_from_file_location("paper_numbers", ROOT / "benchmarks" / "paper_numbers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_jump_time_is_where_the_envelope_stays_above_half_its_final_value():
    # A response at w/2 whose amplitude rises smoothly from 0.1 to 4 around t = 1000 s: the
    # amplitude is half its final value where 0.1 + 3.9 s(t) = 2, s the logistic below.
    pn = paper_numbers_module()
    w = 5.0
    t = np.arange(0.0, 3000.0, 0.02)
    s = 1.0 / (1.0 + np.exp(-(t - 1000.0) / 60.0))
    z = (0.1 + 3.9 * s) * np.sin(0.5 * w * t)
    # an early transient above half the final value must not count: the envelope has to stay up
    z[t < 20] += 3.0 * np.exp(-t[t < 20])
    tj, block, final = pn.jump_time(t, z, w)
    expected = 1000.0 + 60.0 * np.log((2.0 - 0.1) / (4.0 - 2.0))
    assert block == pytest.approx(4 * np.pi / w)
    assert final == pytest.approx(4.0, rel=1e-3)
    assert expected - block <= tj <= expected + block


def test_the_check_reports_every_number_that_changed(tmp_path):
    pn = paper_numbers_module()
    stored = {"a": {"text": "6.56"}, "b": {"text": "5.04"}, "gone": {"text": "1"}}
    (tmp_path / "n.json").write_text(json.dumps({"numbers": stored}))
    now = {"a": {"text": "6.58"}, "b": {"text": "5.04"}, "new": {"text": "2"}}
    diff = pn.compare(now, tmp_path / "n.json")
    assert len(diff) == 3 and any(d.startswith("a: 6.56") for d in diff)
    assert pn.compare(stored, tmp_path / "n.json") == []
    assert pn.compare(now, tmp_path / "missing.json") != []


def test_grid_frequencies_print_to_the_step():
    pn = paper_numbers_module()
    assert [pn.step_decimals(s) for s in (0.02, 0.025, 0.005, 0.5, 1.0)] == [2, 3, 3, 1, 0]
    assert pn.decimals(2 * np.pi / 600) == 2 and pn.decimals(2 * np.pi / 29.2) == 1


def test_every_full_scene_passes_the_cost_check_or_is_forced():
    """`make fig8a` (and so `make figures` and `make paper-numbers`) stopped at the sweep's cost
    check: 81 points of up to 6000 s by the error-controlled scheme's largest step rate is an
    upper bound of 1.96e9 steps, above the 1e9 allowed without --force."""
    from cablesim import api

    sweeps = {}
    for line in dry_run("figures").splitlines():
        if line.startswith("CABLESIM sweep ") and " -o " in line:
            args = shlex.split(line.split("||")[0])[1:]
            sweeps[Path(args[args.index("-o") + 1]).stem] = args
    assert "fig8a" in sweeps and len(sweeps) >= 5
    for scene, args in sweeps.items():
        why = api.sweep_cost(fast_case(args)).excess()
        assert why is None or "--force" in args, (scene, why)


def test_out_of_plane_chapter_quotes_its_computed_numbers():
    """The chapter "Out of the plane" quotes the out-of-plane period doublings and the history
    checks that ``make out-of-plane`` wrote to docs/out-of-plane.json, and those checks hold
    (the history settles on the nonplanar orbit to 1e-4 in amplitude)."""
    text = DOC.read_text().split("## Out of the plane")[1].split("\n## ")[0]
    data = json.loads((ROOT / "docs" / "out-of-plane.json").read_text())
    for case in ("paper", "stay"):
        d = data[case]
        for omega in d["out_of_plane_doublings_rad_s"]:
            assert f"{omega:.5f}" in text, (case, omega)
        assert d["max_w_error"] < 1e-4 and d["state_error"] < 1e-4
        assert d["planar_out_of_plane_multiplier"] > 1 > d["orbit_largest_multiplier"]
        for err in (d["state_error"], d["max_w_error"]):
            assert f"{err:.1e}".replace("e-0", "e-") in text, (case, err)
        assert f"{d['periods']} periods" in text
