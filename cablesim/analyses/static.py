"""Static analysis of a case: the three equilibria under F0, modal analysis, Rayleigh damping."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..cable import Cable
from ..case import Case
from ..case.sections import ALL_MODES_DOF, DEFAULT_MODES
from ..errors import CablesimError
from ..modal import (
    ALL_SHAPES_DOF,
    COUPLED,
    OUT_OF_PLANE,
    Modes,
    equilibrium_plane,
    inextensible_frequencies,
    modal_analysis,
    modal_analysis_banded,
    modal_damping_ratios,
    planar_modes,
    plane_basis,
    rayleigh_coefficients,
    sole_inextensible_frequency,
    with_kinds,
)
from ..statics import (
    ApproximateEquilibrium,
    ExactEquilibrium,
    InextensibleEquilibrium,
    approximate_equilibrium,
    exact_equilibrium,
    inextensible_equilibrium,
)

#: Above this many nodes `cablesim static` computes only the chosen analysis by default: the
#: inextensible and approximate models work with dense 2n x 2n flexibilities (O(n^3)).
ALL_MODELS_NODES = 300
#: Above 2n = ALL_SHAPES_DOF (see cablesim.modal) the exact analysis keeps the shapes of the
#: lowest SHAPES_KEPT modes (or up to the highest mode a free vibration or the damping asks for).
SHAPES_KEPT = 20


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
    a0, a1 : float
        Rayleigh coefficients (1/s and s).
    damping_ratios : ndarray
        Resulting damping ratio of every mode.
    inextensible_omega : ndarray
        The ``n - 1`` finite frequencies of the inextensible cable, rad/s.
    sole_inextensible_omega : float or None
        The paper's closed-form sole inextensible frequency (n = 2 only), rad/s.
    warnings : tuple of str
        Plausibility warnings (a strain of several per cent); they never stop a run.
    K0_band : ndarray or None
        ``K0`` in symmetric lower band form, shape (4, 2n) (exact analysis; see
        :func:`cablesim.statics.tangent_stiffness_band`).
    K0 : ndarray
        The tangent stiffness of the chosen analysis, dense (2n, 2n), N/m: in the exact
        analysis built on first use, so that a heavy cable's statics stay O(n) in memory
        unless something asks for it (``--matrices``, the dense checks of small cables).
    """

    cable: Cable
    analysis: str
    P: np.ndarray
    inextensible: InextensibleEquilibrium | None
    approximate: ApproximateEquilibrium | None
    exact: ExactEquilibrium | None
    modes: Modes
    a0: float
    a1: float
    damping_ratios: np.ndarray
    inextensible_omega: np.ndarray
    sole_inextensible_omega: float | None
    warnings: tuple[str, ...] = ()
    K0_band: np.ndarray | None = None

    @property
    def K0(self) -> np.ndarray:
        """Dense tangent stiffness of the chosen analysis, N/m (see the class docstring)."""
        return self.exact.K if self.analysis == "exact" else self.approximate.K

    @property
    def y0(self) -> np.ndarray:
        """Equilibrium configuration of the chosen analysis, m."""
        return self.exact.y if self.analysis == "exact" else self.approximate.y

    @property
    def T0(self) -> np.ndarray:
        """Segment tensions at equilibrium in the chosen analysis, N."""
        return self.exact.T if self.analysis == "exact" else self.approximate.T


def damping_coefficients(case: Case, modes: Modes) -> tuple[float, float]:
    """Rayleigh ``(a0, a1)`` for a case, given its modes (:func:`damping_modes` says which two)."""
    d = case.damping
    if d.ratio is None:
        return float(d.a0), float(d.a1)
    i, j = damping_modes(case, modes)
    return rayleigh_coefficients(modes.omega[i], modes.omega[j], d.ratio)


def modes_to_compute(case: Case, n_dof: int, n_modes: int | None = None, at_least: int = 0) -> int | None:
    """How many of the lowest modes to compute (None: all).

    ``n_modes`` (``static --modes``), else ``modal.modes`` of the case, else every mode up to
    :data:`~cablesim.case.sections.ALL_MODES_DOF` DOF and the lowest
    :data:`~cablesim.case.sections.DEFAULT_MODES` beyond; never fewer than the modes the
    damping or a free vibration names, nor than ``at_least`` (a mode given on the command line).
    """
    k = n_modes if n_modes is not None else case.modal.modes
    if k is None and n_dof > ALL_MODES_DOF:
        k = DEFAULT_MODES
    if k is None:
        return None
    k = max(int(k), case.free_vibration.mode or 0, at_least, *case.damping.modes)
    return None if k >= n_dof else k


def _modes(case: Case, cable: Cable, K0: np.ndarray | None, K0_band: np.ndarray | None,
           n_modes: int | None, at_least: int, y0: np.ndarray) -> Modes:
    k = modes_to_compute(case, cable.n_dof, n_modes, at_least)
    wanted = max(SHAPES_KEPT, case.free_vibration.mode or 0, at_least, *case.damping.modes)
    n_shapes = None if cable.n_dof <= ALL_SHAPES_DOF else wanted
    if cable.dim == 3:  # in-plane and out-of-plane modes of a planar equilibrium, solved apart
        points = np.vstack([cable.support_A, np.reshape(y0, (-1, 3)), cable.support_B])
        normal = equilibrium_plane(points, cable.chord)
        if normal is not None:
            R = plane_basis(normal, cable.chord)
            if K0_band is None:
                return planar_modes(K0, cable.masses, R, n_modes=k, banded=False)
            return planar_modes(K0_band, cable.masses, R, n_modes=k, n_shapes=n_shapes)
    if K0_band is None:
        modes = modal_analysis(K0, cable.mass_diagonal, n_modes=k)
    else:
        modes = modal_analysis_banded(K0_band, cable.mass_diagonal, n_modes=k, n_shapes=n_shapes)
    return with_kinds(modes, COUPLED) if cable.dim == 3 else modes


def damping_modes(case: Case, modes: Modes) -> tuple[int, int]:
    """The 0-based indices of the two modes ``damping.modes`` names: counted among all modes of a
    planar cable and, of a spatial one, among those that are not out of the plane (a planar case
    made spatial keeps its damping)."""
    i, j = case.damping.modes
    counted = [m for m, kind in enumerate(modes.kinds or ("",) * modes.omega.size) if kind != OUT_OF_PLANE]
    if max(i, j) > len(counted):
        raise CablesimError(f"damping.modes asks for mode {max(i, j)} but the cable has {len(counted)} "
                            f"{'in-plane and coupled ' if modes.kinds else ''}modes.", field="damping.modes")
    return counted[i - 1], counted[j - 1]


def run_static(case: Case, analysis: str | None = None, all_models: bool | None = True,
               n_modes: int | None = None, modes_at_least: int = 0) -> StaticResult:
    """Solve the statics of a case under its sustained loads F0.

    Parameters
    ----------
    case : Case
    analysis : {"exact", "approximate"}, optional
        Overrides ``case.analysis``.
    all_models : bool or None
        Compute every model (for the ``static`` command); ``False`` computes only what the
        chosen analysis needs; None: every model up to ALL_MODELS_NODES nodes.
    n_modes : int, optional
        Compute only the lowest this many modes (and the highest frequency); overrides the
        case's ``modal.modes`` (see :func:`modes_to_compute` for the default).
    modes_at_least : int
        Compute at least this many of the lowest modes, with their shapes (a free vibration's
        ``--mode``).

    Returns
    -------
    StaticResult
    """
    analysis = analysis or case.analysis
    cable = case.to_cable()
    P = case.F0
    if all_models is None:
        all_models = cable.n_nodes <= ALL_MODELS_NODES
    taut = not cable.spans_slack
    if taut and analysis == "approximate":
        raise CablesimError(
            f"cable.S sums to {cable.total_length:.15g} m, not more than the chord "
            f"{cable.chord_length:.15g} m between the supports (within 1e-12): the approximate analysis starts "
            "from the inextensible cable, which cannot span them. Lengthen cable.S, or use "
            "`analysis: exact` for a pretensioned cable.",
            field="cable.S",
        )
    if not taut and not np.any(P):
        raise CablesimError(
            "loads.F0 is all zero. Segment tensions would all be zero (every segment slack): a weightless "
            "cable longer than its chord takes no definite shape without sustained loads, so there is no "
            "equilibrium to solve. Give the sustained nodal loads F0 in N (for instance each node's weight "
            "m*g as its vertical component, positive down); changing cable.S does not help.",
            field="loads.F0",
        )
    inext = approx = exact = None
    if not taut:
        inext = inextensible_equilibrium(cable, P)
        check_resolvable(cable, inext.T)
    if analysis == "approximate" or (all_models and not taut):
        approx = approximate_equilibrium(cable, P)
        inext = approx.inextensible
    if analysis == "exact" or all_models:
        exact = exact_equilibrium(cable, P)
        if taut:
            check_resolvable(cable, exact.T)
    K0_band = exact.K_band if analysis == "exact" else None
    y0 = exact.y if analysis == "exact" else approx.y
    modes = _modes(case, cable, None if K0_band is not None else approx.K, K0_band, n_modes, modes_at_least, y0)
    a0, a1 = damping_coefficients(case, modes)
    inext_omega = np.array([])
    sole = None
    if inext is not None and all_models:
        inext_omega = inextensible_frequencies(inext.D, cable.mass_diagonal, cable.n_nodes)
        if cable.n_nodes == 2 and cable.dim == 2:  # eq. 21, the paper's closed form for a planar 2-node cable
            sole = sole_inextensible_frequency(inext.x, P, inext.T[1], cable.S, cable.masses, cable.L, cable.H)
    return StaticResult(
        cable=cable,
        analysis=analysis,
        P=P,
        inextensible=inext,
        approximate=approx,
        exact=exact,
        modes=modes,
        a0=a0,
        a1=a1,
        damping_ratios=modal_damping_ratios(modes.omega, a0, a1),
        inextensible_omega=inext_omega,
        sole_inextensible_omega=sole,
        warnings=strain_warnings(cable, exact.T if exact is not None else approx.T),
        K0_band=K0_band,
    )


#: Smallest largest strain T/EA that double precision resolves well: below it the elastic
#: stretch l - S is lost in rounding (at 3e-12 the lowest frequency of the paper's example is
#: already 6e-5 off, at 3e-16 40 % off), and the cable is inextensible for all purposes.
MIN_STRAIN = 1e-10
#: Largest strain T/EA before the static summary warns that the model is stretched beyond
#: small strains (linear elasticity of T = EA (l - S) / S).
PLAUSIBLE_STRAIN = 0.05


#: The bound of :data:`PLAUSIBLE_STRAIN` in words, for every warning that cites it.
SMALL_STRAINS_TEXT = f"the {100 * PLAUSIBLE_STRAIN:g} % of the model's small strains (T = EA (l - S) / S)"


def beyond_small_strains(strain) -> np.ndarray:
    """Where a strain ``T / EA`` is beyond the model's range (:data:`PLAUSIBLE_STRAIN`): the one
    rule of the static, history and continuation warnings."""
    return np.asarray(strain, dtype=float) > PLAUSIBLE_STRAIN


def check_resolvable(cable: Cable, T: np.ndarray) -> None:
    """Refuse an EA so large that the strains under the loads are below double precision."""
    strain = float(np.max(np.abs(T))) / cable.EA
    if strain < MIN_STRAIN:
        limit = float(np.max(np.abs(T))) / MIN_STRAIN
        raise CablesimError(
            f"cable.EA = {cable.EA:.4g} N is too stiff for these loads: the largest strain T/EA would be "
            f"{strain:.2g}, below the {MIN_STRAIN:g} that double precision resolves, so the elastic stretch "
            "would be rounding noise (and the frequencies wrong). The cable is inextensible for all "
            f"purposes, and this run is refused rather than treated as inextensible: give cable.EA at "
            f"most {limit:.2g} N (already inextensible in effect), or larger loads.",
            field="cable.EA",
        )


def strain_warnings(cable: Cable, T: np.ndarray) -> tuple[str, ...]:
    """A warning when the static strain exceeds :data:`PLAUSIBLE_STRAIN` (never an error)."""
    strain = np.asarray(T, dtype=float) / cable.EA
    k = int(np.argmax(strain))
    if not beyond_small_strains(strain[k]):
        return ()
    return (
        f"the static strain T/EA of segment {k + 1} is {100 * strain[k]:.3g} % (sum of cable.S "
        f"{cable.total_length:.6g} m, chord {cable.chord_length:.6g} m, EA {cable.EA:.4g} N): the model "
        "assumes small strains, so results beyond a few per cent are not those of a real cable. "
        "Check cable.S, cable.EA and the loads.",
    )
