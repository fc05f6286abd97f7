"""The discrete cable under its own weight approaches Irvine and Caughey's linear theory of the
shallow cable (docs/theory.md, section 6) at order 2 in the number of nodes.

Level supports, sag about 1/160 of the span: first antisymmetric in-plane frequency
``w = 2 pi / L sqrt(H / m)``; first symmetric ``w = beta sqrt(H / m) / L`` with
``tan(beta / 2) = beta / 2 - (4 / lambda^2) (beta / 2)^3`` and
``lambda^2 = (m g L / H)^2 L / (H L_e / EA)``, ``L_e = int (ds/dx)^3 dx``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from cablesim.analyses.static import run_static
from cablesim.case import parse_case

L, G, MPL, LENGTH = 100.0, 9.81, 1.0, 100.004


def irvine_symmetric(lam2: float) -> float:
    """First root beta in (pi, 3 pi) of the symmetric frequency equation."""
    # tan(beta/2) runs continuously from -inf to +inf over (pi, 3 pi): one sign change there.
    f = lambda b: np.tan(b / 2) - b / 2 + 4.0 / lam2 * (b / 2) ** 3  # noqa: E731
    return brentq(f, np.pi * (1 + 1e-12), 3 * np.pi * (1 - 1e-12), xtol=1e-14)


def discrete(n: int, EA: float) -> tuple[float, float, float]:
    """lambda^2 and the first symmetric and antisymmetric beta = w L / sqrt(H / m) of n nodes."""
    case = parse_case(
        f"cable: {{L: {L}, H: 0.0, length: {LENGTH}, nodes: {n}, EA: {EA}, mass_per_length: {MPL}}}\n"
        f"loads: {{gravity: {G}}}\ndamping: {{a0: 0.0, a1: 0.0}}\n"
    )
    r = run_static(case, "exact", all_models=False)
    d = np.diff(np.concatenate([[0.0, 0.0], r.exact.y, [L, 0.0]]).reshape(-1, 2), axis=0)
    H = r.exact.T[0] * d[0, 0] / np.hypot(*d[0])  # horizontal tension, the same in every segment
    m = MPL * LENGTH / L  # mass per unit span
    Le = np.sum(np.hypot(d[:, 0], d[:, 1]) ** 3 / d[:, 0] ** 2)
    lam2 = (m * G * L / H) ** 2 * L / (H * Le / EA)
    vert = r.modes.shapes[1::2]
    sym = np.abs(vert + vert[::-1]).sum(axis=0) > np.abs(vert - vert[::-1]).sum(axis=0)
    scale = L / np.sqrt(H / m)
    return lam2, r.modes.omega[sym][0] * scale, r.modes.omega[~sym][0] * scale


@pytest.mark.parametrize("EA", [1.0e8, 1.0e9], ids=["below-crossover", "above-crossover"])
def test_symmetric_frequency_converges_at_order_2(EA):
    err = []
    for n in (9, 19, 39):  # 10, 20, 40 segments
        lam2, sym, _ = discrete(n, EA)
        err.append(sym / irvine_symmetric(lam2) - 1.0)
    assert 3.5 < err[0] / err[1] < 4.5 and 3.5 < err[1] / err[2] < 4.5, err
    assert abs(err[2]) < 5e-4
    # Irvine's crossover at lambda^2 = 4 pi^2: the symmetric mode passes the antisymmetric one.
    _, sym, anti = discrete(39, EA)
    assert (sym < anti) == (lam2 < 4 * np.pi**2)


def test_antisymmetric_frequency_converges_at_order_2():
    beta = [discrete(n, 3.0e8)[2] for n in (19, 39, 79)]
    d1, d2 = beta[1] - beta[0], beta[2] - beta[1]
    assert 3.5 < d1 / d2 < 4.5, (d1, d2)
    limit = beta[2] + d2 / 3.0  # Richardson: the n -> infinity value
    # 2 pi within the shallow-cable theory's own error, O((sag / span)^2)
    assert limit / (2 * np.pi) - 1.0 == pytest.approx(0.0, abs=5e-4)
