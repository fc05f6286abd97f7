"""A frequency sweep and the response at its peak: five forcing frequencies around the first
resonance of the paper's example, the frequency response drawn, a time history at the frequency
of the largest response, animated over its steady period, and one HTML report of both runs.

Run from the repository: ``.venv/bin/python examples/sweep.py [FOLDER]``
(default folder: ``runs/examples/sweep``). About ten seconds.
"""

import sys
from pathlib import Path

import numpy as np

import cablesim

out = Path(sys.argv[1] if len(sys.argv) > 1 else "runs/examples/sweep")

case = cablesim.load_case(None, overrides=[
    "sweep.omega=[2.2, 2.35, 2.45, 2.55, 2.7]",  # rad/s
    "sweep.refine=false", "sweep.duration=400", "sweep.window=80",  # s
])
sw = cablesim.sweep(case, jobs=1)
h5 = sw.to_hdf5(out / "sweep.h5")
png = sw.plot(out / "sweep.png", h5)

amplitude = sw.result.table(0).amplitude[:, 0]  # peak |z| of the first channel, m
k = int(np.nanargmax(amplitude))
omega = float(sw.result.omega[k])
for w, a in zip(sw.result.omega, amplitude):
    print(f"  omega = {w:.3f} rad/s: peak |{sw.result.channels[0]}| = {a:.3f} m" + ("  <- largest" if w == omega else ""))

h = cablesim.history(case, omega=omega, duration=300.0)   # the response at that frequency
hist = h.to_hdf5(out / f"history-w{omega:g}.h5")
h.plot(out / f"history-w{omega:g}")
anim = cablesim.animate(hist, out / f"history-w{omega:g}-animation.gif", frames=40, fps=15)
print(f"animation: {anim.summary}")

page = cablesim.report([h5, hist], out / "sweep-report.html")
print(f"wrote {h5}, {png}, {hist} and {page}")
