"""The Irvine crossover: first symmetric and antisymmetric in-plane frequencies of a heavy cable
against lambda^2, the discrete cable beside Irvine and Caughey's closed form.

A level 100 m span, 1 kg/m, EA = 3e8 N, under its own weight (case-file shorthand), n interior
nodes; the natural length swept from 99.9 m (pretensioned, sag 4 cm) to 100.06 m (sag 1/65 of
the span), so that lambda^2 runs from about 0.01 to 500. Frequencies
are drawn as beta = w L / sqrt(H / m) (H the horizontal tension, m the mass per unit span):
the antisymmetric one is 2 pi in the shallow theory, the symmetric one solves
``tan(beta/2) = beta/2 - (4/lambda^2)(beta/2)^3`` and crosses it at lambda^2 = 4 pi^2.

Usage::

    .venv/bin/python benchmarks/irvine_crossover.py [-o docs/irvine-crossover.png] [--nodes 39]
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.optimize import brentq  # noqa: E402

from cablesim.analyses.static import run_static  # noqa: E402
from cablesim.case import parse_case  # noqa: E402

L, G, MPL, EA = 100.0, 9.81, 1.0, 3.0e8


def irvine_symmetric(lam2: float) -> float:
    # tan(beta/2) runs continuously from -inf to +inf over (pi, 3 pi): one sign change there.
    f = lambda b: np.tan(b / 2) - b / 2 + 4.0 / lam2 * (b / 2) ** 3  # noqa: E731
    return brentq(f, np.pi * (1 + 1e-12), 3 * np.pi * (1 - 1e-12), xtol=1e-14)


def discrete(n: int, length: float) -> tuple[float, float, float]:
    case = parse_case(
        f"cable: {{L: {L}, H: 0.0, length: {length}, nodes: {n}, EA: {EA}, mass_per_length: {MPL}}}\n"
        f"loads: {{gravity: {G}}}\ndamping: {{a0: 0.0, a1: 0.0}}\n"
    )
    r = run_static(case, "exact", all_models=False)
    d = np.diff(np.concatenate([[0.0, 0.0], r.exact.y, [L, 0.0]]).reshape(-1, 2), axis=0)
    H = r.exact.T[0] * d[0, 0] / np.hypot(*d[0])
    m = MPL * length / L
    Le = np.sum(np.hypot(d[:, 0], d[:, 1]) ** 3 / d[:, 0] ** 2)
    lam2 = (m * G * L / H) ** 2 * L / (H * Le / EA)
    vert = r.modes.shapes[1::2]
    sym = np.abs(vert + vert[::-1]).sum(axis=0) > np.abs(vert - vert[::-1]).sum(axis=0)
    scale = L / np.sqrt(H / m)
    return lam2, r.modes.omega[sym][0] * scale, r.modes.omega[~sym][0] * scale


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-o", "--output", default="docs/irvine-crossover.png")
    ap.add_argument("--nodes", type=int, action="append", help="node counts (default 9 and 39)")
    args = ap.parse_args(argv)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for n, mark in zip(args.nodes or [9, 39], "ox^s"):
        pts = np.array([discrete(n, 99.9 + d) for d in np.geomspace(1e-3, 0.16, 36)])
        ax.plot(pts[:, 0], pts[:, 1], mark, ms=4, mfc="none", label=f"n = {n}: first symmetric")
        ax.plot(pts[:, 0], pts[:, 2], mark, ms=4, label=f"n = {n}: first antisymmetric")
    lam2 = np.geomspace(min(pts[:, 0].min(), 0.1), 600, 400)
    ax.plot(lam2, [irvine_symmetric(x) for x in lam2], "k-", lw=1, label="Irvine-Caughey: symmetric")
    ax.axhline(2 * np.pi, color="k", ls="--", lw=1, label="Irvine-Caughey: antisymmetric, 2 pi")
    ax.axvline(4 * np.pi**2, color="grey", ls=":", lw=1)
    ax.text(4 * np.pi**2 * 1.05, 3.4, "lambda^2 = 4 pi^2", color="grey")
    ax.set_xscale("log")
    ax.set_xlabel("lambda^2")
    ax.set_ylabel("beta = w L / sqrt(H / m)")
    ax.set_title("Irvine crossover: lumped heavy cable and the shallow-cable theory", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(args.output, dpi=120)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
