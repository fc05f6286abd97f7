"""Statics to figures: the paper's example cable under its sustained loads, its tensions and
modes printed, the result file, the drawing of the cable, its lowest mode shapes and a one-page
HTML report of the run.

Run from the repository: ``.venv/bin/python examples/statics_to_figures.py [FOLDER]``
(default folder: ``runs/examples/statics``).
"""

import math
import sys
from pathlib import Path

import cablesim

out = Path(sys.argv[1] if len(sys.argv) > 1 else "runs/examples/statics")

case = cablesim.load_case()  # the paper's example; or a case file's path, or a dict
run = cablesim.static(case)
result = run.result

print(f"{case.name}: {result.cable.n_nodes} nodes, {result.analysis} analysis")
for k, T in enumerate(result.T0, start=1):
    print(f"  segment {k}: T = {T / 1e3:.1f} kN")
for k, (w, xi) in enumerate(zip(result.modes.omega, result.damping_ratios), start=1):
    print(f"  mode {k}: {w:.4f} rad/s = {w / (2 * math.pi):.4f} Hz, damping ratio {xi:.4f}")

h5 = run.to_hdf5(out / "static.h5")            # the file `cablesim static` writes
png = run.plot(out / "static.png")             # the cable under its loads
fig = run.plot_modes(out / "static-modes.png", count=4)   # a matplotlib Figure, also saved
page = cablesim.report([h5], out / "static-report.html")  # tables and both figures, one HTML page
print(f"wrote {h5}, {png}, {out / 'static-modes.png'} ({len(fig.axes)} panels) and {page}")
