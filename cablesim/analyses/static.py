"""Static analysis of a case: the three equilibria under F0, modal analysis, Rayleigh damping."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..cable import Cable
from ..case import Case
from ..errors import CablesimError
from ..modal import (
    Modes,
    inextensible_frequencies,
    modal_analysis,
    modal_damping_ratios,
    rayleigh_coefficients,
    sole_inextensible_frequency,
)
from ..statics import (
    ApproximateEquilibrium,
    ExactEquilibrium,
    InextensibleEquilibrium,
    approximate_equilibrium,
    exact_equilibrium,
    inextensible_equilibrium,
)


@dataclass(frozen=True)
class StaticResult:
    """Everything the static analysis of a case finds.

    Attributes
    ----------
    cable : Cable
    analysis : str
        ``"exact"`` or ``"approximate"``: the model whose tangent stiffness gives the modes.
    P : ndarray
        The sustained loads F0, N.
    inextensible : InextensibleEquilibrium or None
        None for a pretensioned cable shorter than its chord (no inextensible state exists).
    approximate : ApproximateEquilibrium or None
    exact : ExactEquilibrium or None
        None when the approximate analysis was asked for and the exact one was not needed.
    modes : Modes
        Linear modes from the tangent stiffness ``K0`` of the chosen analysis.
    K0 : ndarray
        That tangent stiffness, N/m.
    a0, a1 : float
        Rayleigh coefficients (1/s and s).
    damping_ratios : ndarray
        Resulting damping ratio of every mode.
    inextensible_omega : ndarray
        The ``n - 1`` finite frequencies of the inextensible cable, rad/s.
    sole_inextensible_omega : float or None
        The paper's closed-form sole inextensible frequency (n = 2 only), rad/s.
    """

    cable: Cable
    analysis: str
    P: np.ndarray
    inextensible: InextensibleEquilibrium | None
    approximate: ApproximateEquilibrium | None
    exact: ExactEquilibrium | None
    modes: Modes
    K0: np.ndarray
    a0: float
    a1: float
    damping_ratios: np.ndarray
    inextensible_omega: np.ndarray
    sole_inextensible_omega: float | None

    @property
    def y0(self) -> np.ndarray:
        """Equilibrium configuration of the chosen analysis, m."""
        return self.exact.y if self.analysis == "exact" else self.approximate.y

    @property
    def T0(self) -> np.ndarray:
        """Segment tensions at equilibrium in the chosen analysis, N."""
        return self.exact.T if self.analysis == "exact" else self.approximate.T


def damping_coefficients(case: Case, omega: np.ndarray) -> tuple[float, float]:
    """Rayleigh ``(a0, a1)`` for a case, given the modal frequencies (rad/s)."""
    d = case.damping
    if d.ratio is None:
        return float(d.a0), float(d.a1)
    i, j = d.modes
    if max(i, j) > omega.size:
        raise CablesimError(f"damping.modes asks for mode {max(i, j)} but the cable has {omega.size}.")
    return rayleigh_coefficients(omega[i - 1], omega[j - 1], d.ratio)


def run_static(case: Case, analysis: str | None = None, all_models: bool = True) -> StaticResult:
    """Solve the statics of a case under its sustained loads F0.

    Parameters
    ----------
    case : Case
    analysis : {"exact", "approximate"}, optional
        Overrides ``case.analysis``.
    all_models : bool
        Compute every model (for the ``static`` command); ``False`` computes only what the
        chosen analysis needs.

    Returns
    -------
    StaticResult
    """
    analysis = analysis or case.analysis
    cable = case.to_cable()
    P = case.F0
    taut = cable.total_length <= cable.chord_length
    if taut and analysis == "approximate":
        raise CablesimError(
            f"cable.S sums to {cable.total_length:.6g} m, not more than the chord "
            f"{cable.chord_length:.6g} m between the supports: the approximate analysis starts "
            "from the inextensible cable, which cannot span them. Lengthen cable.S, or use "
            "`analysis: exact` for a pretensioned cable.",
            field="cable.S",
        )
    inext = approx = exact = None
    if analysis == "approximate" or (all_models and not taut):
        approx = approximate_equilibrium(cable, P)
        inext = approx.inextensible
    elif not taut:
        inext = inextensible_equilibrium(cable, P)
    if analysis == "exact" or all_models:
        exact = exact_equilibrium(cable, P)
    K0 = exact.K if analysis == "exact" else approx.K
    modes = modal_analysis(K0, cable.mass_diagonal)
    a0, a1 = damping_coefficients(case, modes.omega)
    inext_omega = np.array([])
    sole = None
    if inext is not None:
        inext_omega = inextensible_frequencies(inext.D, cable.mass_diagonal)
        if cable.n_nodes == 2:
            sole = sole_inextensible_frequency(inext.x, P, inext.T[1], cable.S, cable.masses, cable.L, cable.H)
    return StaticResult(
        cable=cable,
        analysis=analysis,
        P=P,
        inextensible=inext,
        approximate=approx,
        exact=exact,
        modes=modes,
        K0=K0,
        a0=a0,
        a1=a1,
        damping_ratios=modal_damping_ratios(modes.omega, a0, a1),
        inextensible_omega=inext_omega,
        sole_inextensible_omega=sole,
    )
