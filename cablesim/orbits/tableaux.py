"""Butcher tableaux of the fixed-step explicit Runge-Kutta schemes used for shooting.

Each scheme is integrated together with its variational equations (internal numerical
differentiation), so the computed monodromy matrix is the exact derivative of the discrete
flow map: Newton's method on the periodicity condition converges quadratically whatever the
step, and the step only sets how closely the discrete orbit follows the true one.

- ``rk4``: the classical fourth-order method (4 stages).
- ``rk8``: the eighth-order 12-stage method of Dormand and Prince's DOP853 pair (Hairer,
  Norsett and Wanner, *Solving ODEs I*, 2nd ed.), used here with a fixed step and without its
  embedded error estimate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Tableau:
    """An explicit Runge-Kutta scheme ``(A, b, c)`` of the given order.

    ``stability_limit`` is (about) the largest ``h |lambda|`` for an oscillatory (imaginary)
    eigenvalue ``lambda`` that the scheme integrates without growth.
    """

    name: str
    order: int
    A: np.ndarray
    b: np.ndarray
    c: np.ndarray
    stability_limit: float

    @property
    def stages(self) -> int:
        return self.b.size


def _rk4() -> Tableau:
    A = np.zeros((4, 4))
    A[1, 0] = 0.5
    A[2, 1] = 0.5
    A[3, 2] = 1.0
    b = np.array([1.0, 2.0, 2.0, 1.0]) / 6.0
    c = np.array([0.0, 0.5, 0.5, 1.0])
    return Tableau("rk4", 4, A, b, c, 2.8)


def _rk8() -> Tableau:
    A = np.zeros((12, 12))
    rows = [
        [],
        [0.05260015195876773],
        [0.0197250569845379, 0.0591751709536137],
        [0.02958758547680685, 0.0, 0.08876275643042054],
        [0.2413651341592667, 0.0, -0.8845494793282861, 0.924834003261792],
        [0.037037037037037035, 0.0, 0.0, 0.17082860872947386, 0.12546768756682242],
        [0.037109375, 0.0, 0.0, 0.17025221101954405, 0.06021653898045596, -0.017578125],
        [0.03709200011850479, 0.0, 0.0, 0.17038392571223998, 0.10726203044637328,
         -0.015319437748624402, 0.008273789163814023],
        [0.6241109587160757, 0.0, 0.0, -3.3608926294469414, -0.868219346841726,
         27.59209969944671, 20.154067550477894, -43.48988418106996],
        [0.47766253643826434, 0.0, 0.0, -2.4881146199716677, -0.590290826836843,
         21.230051448181193, 15.279233632882423, -33.28821096898486, -0.020331201708508627],
        [-0.9371424300859873, 0.0, 0.0, 5.186372428844064, 1.0914373489967295,
         -8.149787010746927, -18.52006565999696, 22.739487099350505, 2.4936055526796523,
         -3.0467644718982196],
        [2.273310147516538, 0.0, 0.0, -10.53449546673725, -2.0008720582248625,
         -17.9589318631188, 27.94888452941996, -2.8589982771350235, -8.87285693353063,
         12.360567175794303, 0.6433927460157636],
    ]
    for i, r in enumerate(rows):
        A[i, : len(r)] = r
    b = np.array([
        0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
        -5.801203960010585, 0.3111643669578199, -0.1521609496625161, 0.20136540080403034,
        0.04471061572777259,
    ])
    c = A.sum(axis=1)  # row sums (consistent to round-off with the published nodes)
    return Tableau("rk8", 8, A, b, c, 3.5)


TABLEAUX: dict[str, Tableau] = {t.name: t for t in (_rk4(), _rk8())}
