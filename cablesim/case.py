"""Case files: YAML in, a frozen and validated :class:`Case` out.

A case file describes one cable, its loads, the analysis and the damping (SI units throughout:
m, N, kg, s, rad/s). Unknown keys are errors, so a misspelt key is never silently ignored.
:func:`load_case` turns every problem into a :class:`~cablesim.errors.CablesimError` whose
message names the field and says what to do.
"""

from __future__ import annotations

import math
import re
from importlib import resources
from pathlib import Path
from typing import Any, Literal

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator, model_validator

from .cable import Cable
from .errors import CablesimError
from .names import ANALYSES, DIRECTIONS, INTEGRATORS

EXAMPLE_RESOURCE = "paper-example.yaml"


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


def _finite(v: float, what: str) -> float:
    if not math.isfinite(v):
        raise ValueError(f"{what} must be a finite number")
    return v


class CableSpec(_Strict):
    """Geometry, axial rigidity and masses (section ``cable:``)."""

    L: float = Field(gt=0, description="horizontal distance A->B, m")
    H: float = Field(description="vertical distance A->B, m, positive = B below A")
    S: tuple[float, ...] = Field(min_length=2, description="natural segment lengths, m (n+1)")
    EA: float | None = Field(default=None, gt=0, description="axial rigidity, N")
    E: float | None = Field(default=None, gt=0, description="Young's modulus, N/m^2")
    A: float | None = Field(default=None, gt=0, description="cross-section area, m^2")
    masses: tuple[float, ...] = Field(min_length=1, description="lumped nodal masses, kg (n)")

    @field_validator("S", "masses")
    @classmethod
    def _positive(cls, v, info):
        for i, x in enumerate(v):
            if not math.isfinite(x) or x <= 0:
                raise ValueError(f"every value must be a positive finite number; item {i + 1} is {x}")
        return v

    @model_validator(mode="after")
    def _rigidity_and_sizes(self):
        if self.EA is None and (self.E is None or self.A is None):
            raise ValueError("give the axial rigidity as EA (N), or as both E (N/m^2) and A (m^2)")
        if self.EA is not None and (self.E is not None or self.A is not None):
            raise ValueError("give either EA or E and A, not both")
        ea = self.axial_rigidity
        if not math.isfinite(ea) or ea <= 0 or ea < 1e-300:
            raise ValueError(
                f"the axial rigidity E*A = {ea:g} N is out of range; give EA (N) or E and A whose "
                "product is a positive finite number"
            )
        if len(self.masses) != len(self.S) - 1:
            raise ValueError(
                f"cable.masses has {len(self.masses)} values but cable.S has {len(self.S)} "
                f"segments: n+1 segments need n = {len(self.S) - 1} masses, one per interior node"
            )
        return self

    @property
    def axial_rigidity(self) -> float:
        """EA, N."""
        return float(self.EA if self.EA is not None else self.E * self.A)

    @property
    def n_nodes(self) -> int:
        """Number of interior nodes."""
        return len(self.S) - 1


class LoadsSpec(_Strict):
    """Sustained and harmonic nodal loads (section ``loads:``), N, 2n values each."""

    F0: tuple[float, ...] = Field(description="sustained nodal loads, N")
    FL: tuple[float, ...] | None = Field(default=None, description="peak harmonic loads, N")


class DampingSpec(_Strict):
    """Rayleigh damping ``C = a0 M + a1 K0`` (section ``damping:``).

    Either a damping ratio for two modes (default: 1 and 2) or the coefficients themselves.
    """

    ratio: float | None = Field(default=None, ge=0, lt=1, description="damping ratio xi")
    modes: tuple[int, int] = Field(default=(1, 2), description="the two modes given ratio xi")
    a0: float | None = Field(default=None, ge=0, description="mass-proportional coefficient, 1/s")
    a1: float | None = Field(default=None, ge=0, description="stiffness-proportional coefficient, s")

    @model_validator(mode="after")
    def _one_way(self):
        explicit = self.a0 is not None or self.a1 is not None
        if explicit and self.ratio is not None:
            raise ValueError("give damping either as ratio (with modes) or as a0 and a1, not both")
        if explicit and (self.a0 is None or self.a1 is None):
            raise ValueError("explicit Rayleigh damping needs both a0 and a1")
        if not explicit and self.ratio is None:
            raise ValueError("give damping.ratio (e.g. 0.01), or a0 and a1")
        if self.modes[0] < 1 or self.modes[1] < 1 or self.modes[0] == self.modes[1]:
            raise ValueError("damping.modes must be two different mode numbers counted from 1")
        return self




class IntegratorSpec(_Strict):
    """Time-integration scheme and its settings (section ``integrator:``).

    Without a name cablesim chooses: ``dopri5`` for ordinary cables, ``generalized-alpha`` for
    stiff ones (highest mode over 200 times the frequency of interest).
    """

    name: Literal[INTEGRATORS] | None = None
    dt: float | None = Field(default=None, gt=0, description="fixed step, s (rk4, newmark, generalized-alpha)")
    rtol: float | None = Field(default=None, gt=0, lt=1, description="relative tolerance (dopri5)")
    atol: float | None = Field(default=None, gt=0, description="absolute displacement tolerance, m (dopri5)")
    rho_inf: float | None = Field(default=None, ge=0, le=1, description="spectral radius (generalized-alpha)")

    @model_validator(mode="after")
    def _fits(self):
        if self.name in ("rk4", "newmark", "generalized-alpha") and (self.rtol or self.atol):
            raise ValueError(f"integrator.rtol and atol apply to dopri5, not {self.name} (it uses dt)")
        if self.name == "dopri5" and self.dt is not None:
            raise ValueError("dopri5 adapts its step; give rtol/atol instead of integrator.dt")
        if self.rho_inf is not None and self.name not in (None, "generalized-alpha"):
            raise ValueError("integrator.rho_inf applies to generalized-alpha only")
        return self


class HistorySpec(_Strict):
    """Forced response at one frequency (section ``history:``)."""

    omega: float | None = Field(default=None, gt=0, description="forcing frequency, rad/s")
    duration: float = Field(default=600.0, gt=0, description="simulated time, s")
    output_step: float | None = Field(default=None, gt=0, description="interval between saved instants, s")
    channels: tuple[str, ...] | None = Field(default=None, description="DOF to plot, e.g. [z2, z4]")


class FreeVibrationSpec(_Strict):
    """Free vibration about the equilibrium (section ``free_vibration:``).

    Either ``mode`` with ``peak_velocity``, or explicit initial conditions ``z0``/``v0``.
    """

    mode: int | None = Field(default=None, ge=1, description="linear mode giving the initial velocities")
    peak_velocity: float | None = Field(default=None, gt=0, description="largest initial velocity, m/s")
    z0: tuple[float, ...] | None = Field(default=None, description="initial displacement from equilibrium, m")
    v0: tuple[float, ...] | None = Field(default=None, description="initial velocities, m/s")
    damping_ratio: float | None = Field(default=None, ge=0, lt=1, description="overrides damping.ratio")
    duration: float = Field(default=20.0, gt=0, description="simulated time, s")
    output_step: float | None = Field(default=None, gt=0, description="interval between saved instants, s")
    channels: tuple[str, ...] | None = Field(default=None, description="DOF to plot, e.g. [z2, z4]")

    @model_validator(mode="after")
    def _one_way(self):
        explicit = self.z0 is not None or self.v0 is not None
        if explicit and (self.mode is not None or self.peak_velocity is not None):
            raise ValueError("give either mode with peak_velocity, or z0/v0, not both")
        return self


class OmegaGrid(_Strict):
    """An evenly spaced frequency grid, rad/s: ``num`` points from ``start`` to ``stop``."""

    start: float = Field(gt=0, description="first frequency, rad/s")
    stop: float = Field(gt=0, description="last frequency, rad/s")
    num: int = Field(ge=1, le=1_000_000, description="number of points")

    @model_validator(mode="after")
    def _order(self):
        if self.num > 1 and self.stop <= self.start:
            raise ValueError("sweep.omega.stop must be greater than start")
        return self


class SweepSpec(_Strict):
    """Frequency-domain response sweep (section ``sweep:``)."""

    omega: Any = Field(description="grid {start, stop, num} or a list, rad/s")
    duration: float = Field(default=3000.0, gt=0, description="cap on simulated seconds per point")
    window: float = Field(default=200.0, gt=0, description="seconds at the end used when not steady")
    direction: Literal[DIRECTIONS] = "independent"
    channels: tuple[str, ...] | None = Field(default=None, description="DOF reported, e.g. [z2, z4]")
    gamma: tuple[float, ...] | None = Field(default=None, description="scales of FL, one curve each")
    tol: float = Field(default=1e-5, gt=0, lt=0.1, description="relative periodicity tolerance")
    max_period: int = Field(default=6, ge=1, le=50, description="largest response period sought")
    floquet: bool = Field(default=True, description="check the stability of periodic responses")

    @field_validator("omega", mode="before")
    @classmethod
    def _grid(cls, v):
        # One of two forms; parse it here so that an error speaks of the form the user wrote.
        if isinstance(v, dict):
            try:
                return OmegaGrid.model_validate(v)
            except ValidationError as err:
                e = err.errors()[0]
                where = ".".join(str(x) for x in e["loc"])
                msg = _HINTS.get(e["type"], e["msg"].removeprefix("Value error, "))
                raise ValueError(f"{where + ': ' if where else ''}{msg}") from None
        if isinstance(v, (list, tuple)):
            if len(v) == 0:
                raise ValueError("the frequency list is empty; give at least one frequency")
            out = []
            for i, w in enumerate(v):
                try:
                    w = float(w)
                except (TypeError, ValueError):
                    raise ValueError(f"item {i + 1} ({w!r}) is not a number") from None
                if not math.isfinite(w) or w <= 0:
                    raise ValueError(f"frequencies must be positive (rad/s); item {i + 1} is {w}")
                out.append(w)
            return tuple(out)
        raise ValueError("give a grid {start: .., stop: .., num: ..} or a list of frequencies in rad/s")

    @field_validator("gamma")
    @classmethod
    def _gamma(cls, v):
        if v is not None:
            if len(v) == 0:
                raise ValueError("gamma is empty; omit it or give at least one scale")
            for i, g in enumerate(v):
                if not math.isfinite(g) or g <= 0:
                    raise ValueError(f"gamma values scale FL and must be positive; item {i + 1} is {g}")
        return v

    @model_validator(mode="after")
    def _window(self):
        if self.window > self.duration:
            raise ValueError(
                f"sweep.window ({self.window:g} s) is longer than sweep.duration ({self.duration:g} s); "
                "the window is the final part of each point's run, so shorten it"
            )
        return self

    def frequencies(self) -> np.ndarray:
        """The frequency grid, rad/s (ascending for up/down sweeps)."""
        if isinstance(self.omega, OmegaGrid):
            g = self.omega
            return np.linspace(g.start, g.stop, g.num)
        w = np.array(self.omega, dtype=float)
        return np.sort(w) if self.direction != "independent" else w


class OutputsSpec(_Strict):
    """What time-history files keep (section ``outputs:``): a scene saves only what it draws."""

    channels: tuple[str, ...] | None = Field(default=None, description="DOF saved (default: all)")
    split: bool = Field(default=True, description="compute and save the configurational/elastic split")


FIGURE_KINDS = ("fdr", "waveform", "waveform_phase", "waveform_fft", "split", "lissajous_tension")


class FigureSpec(_Strict):
    """A composite figure drawn from stored results by ``cablesim plot`` (section ``figure:``).

    Kinds: ``fdr`` (frequency response from sweep files), ``waveform`` (z(t) of the channels),
    ``waveform_phase`` (z(t) beside the phase plot z vs z'), ``waveform_fft`` (z(t) beside its
    spectrum), ``split`` (z with its configurational and elastic parts), ``lissajous_tension``
    (z_i vs z_j beside tension waveforms). Several result files make one column each.
    """

    kind: Literal["fdr", "waveform", "waveform_phase", "waveform_fft", "split", "lissajous_tension"]
    title: str | None = Field(default=None, description="figure title")
    channels: tuple[str, ...] | None = Field(default=None, description="DOF drawn, e.g. [z2]")
    pair: tuple[str, str] | None = Field(default=None, description="Lissajous pair, e.g. [z2, z4]")
    segments: tuple[int, ...] | None = Field(default=None, description="tension segments drawn (1-based)")
    time_window: tuple[float, float] | None = Field(default=None, description="time axis limits, s")
    labels: tuple[str, ...] | None = Field(default=None, description="one caption per result file")


class Case(_Strict):
    """One analysis case, as read from a YAML case file."""

    name: str | None = Field(default=None, description="case name; default: the file stem")
    cable: CableSpec
    loads: LoadsSpec
    analysis: Literal[ANALYSES] = "exact"
    damping: DampingSpec = DampingSpec(ratio=0.01)
    integrator: IntegratorSpec = IntegratorSpec()
    history: HistorySpec = HistorySpec()
    free_vibration: FreeVibrationSpec = FreeVibrationSpec()
    sweep: SweepSpec | None = None
    outputs: OutputsSpec = OutputsSpec()
    figure: FigureSpec | None = None
    _text: str = PrivateAttr(default="")

    @property
    def text(self) -> str:
        """The YAML text this case was read from (with any ``--set`` overrides recorded), stored
        with every result so that it can be rerun."""
        return self._text

    @field_validator("name")
    @classmethod
    def _safe_name(cls, v):
        if v is not None and not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]*", v):
            raise ValueError("use letters, digits, '.', '_' and '-' only (it names the output folder)")
        return v

    @model_validator(mode="after")
    def _sizes(self):
        n = self.cable.n_nodes
        for key in ("F0", "FL"):
            v = getattr(self.loads, key)
            if v is not None and len(v) != 2 * n:
                raise ValueError(
                    f"loads.{key} has {len(v)} values; this cable has n = {n} interior nodes, so it "
                    f"needs 2n = {2 * n} (horizontal, vertical for each node in turn)"
                )
        if self.damping.modes[1] > 2 * n or self.damping.modes[0] > 2 * n:
            raise ValueError(f"damping.modes must be between 1 and 2n = {2 * n}")
        fv = self.free_vibration
        for key in ("z0", "v0"):
            v = getattr(fv, key)
            if v is not None and len(v) != 2 * n:
                raise ValueError(f"free_vibration.{key} has {len(v)} values; it needs 2n = {2 * n}")
        if fv.mode is not None and fv.mode > 2 * n:
            raise ValueError(f"free_vibration.mode must be between 1 and 2n = {2 * n}")
        return self

    # -- derived objects ---------------------------------------------------------------------
    def to_cable(self) -> Cable:
        """The :class:`~cablesim.cable.Cable` this case describes."""
        c = self.cable
        return Cable(c.L, c.H, np.array(c.S), c.axial_rigidity, np.array(c.masses))

    @property
    def F0(self) -> np.ndarray:
        """Sustained loads, N."""
        return np.array(self.loads.F0, dtype=float)

    @property
    def FL(self) -> np.ndarray:
        """Peak harmonic loads, N (zeros if not given)."""
        if self.loads.FL is None:
            return np.zeros(2 * self.cable.n_nodes)
        return np.array(self.loads.FL, dtype=float)


# ----------------------------------------------------------------------------------------------
# YAML
# ----------------------------------------------------------------------------------------------
class _Loader(yaml.SafeLoader):
    """YAML 1.1 reads ``1.0e9`` as a string; people write numbers that way, so accept it."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(
        r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
        |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
        |\.[0-9_]+(?:[eE][-+][0-9]+)?
        |[-+]?\.(?:inf|Inf|INF)
        |\.(?:nan|NaN|NAN))$""",
        re.X,
    ),
    list("-+0123456789."),
)


def _field_name(loc) -> str:
    parts = []
    for p in loc:
        if isinstance(p, int):
            parts.append(f"[{p + 1}]")
        else:
            parts.append(("." if parts else "") + str(p))
    return "".join(parts) or "(top level)"


_HINTS = {
    "extra_forbidden": "is not a known key; check its spelling and indentation "
    "(`cablesim example` prints a complete case file)",
    "missing": "is required; add it",
    "finite_number": "must be a finite number, not NaN or infinity",
}


def format_validation_error(err: ValidationError, source: str) -> str:
    """One readable paragraph for every problem pydantic found in a case file."""
    items = []
    for e in err.errors():
        field = _field_name(e["loc"])
        msg = _HINTS.get(e["type"])
        if msg is None:
            msg = e["msg"].removeprefix("Value error, ")
            if "input" in e and e["type"] not in ("model_type",) and not isinstance(e["input"], dict):
                msg += f" (got {e['input']!r})"
        items.append(f"`{field}` {msg}" if e["loc"] else msg)
    return f"Case file {source} is not valid: " + "; ".join(items) + "."


def apply_overrides(data: dict, overrides, source: str) -> dict:
    """Set dotted keys (``sweep.omega.num=56``) in a parsed case, values read as YAML."""
    for item in overrides or ():
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise CablesimError(f"--set takes KEY=VALUE with a dotted key (e.g. sweep.duration=1000); got {item!r}.")
        parts = key.strip().split(".")
        node = data
        for part in parts[:-1]:
            child = node.get(part) if isinstance(node, dict) else None
            if child is None:
                child = node[part] = {}
            if not isinstance(child, dict):
                raise CablesimError(f"--set {key}: `{part}` in {source} is not a section.")
            node = child
        try:
            node[parts[-1]] = yaml.load(value, Loader=_Loader)
        except yaml.YAMLError:
            raise CablesimError(f"--set {key}: the value {value!r} is not valid YAML.") from None
    return data


def parse_case(text: str, source: str = "<case>", default_name: str = "case", overrides=None) -> Case:
    """Parse and validate the YAML text of a case file.

    Parameters
    ----------
    text : str
        YAML text.
    source : str
        How to name the file in messages.
    default_name : str
        The case name if the file gives none.
    overrides : list of str, optional
        ``KEY=VALUE`` settings applied over the file (command-line ``--set``).

    Returns
    -------
    Case

    Raises
    ------
    CablesimError
        For malformed YAML or any invalid field.
    """
    try:
        data = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:
        where = ""
        mark = getattr(exc, "problem_mark", None)
        if mark is not None:
            where = f" at line {mark.line + 1}, column {mark.column + 1}"
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise CablesimError(
            f"Case file {source} is not valid YAML{where}: {problem}. Check indentation and that "
            "lists are written [a, b, c]."
        ) from None
    if not isinstance(data, dict):
        raise CablesimError(
            f"Case file {source} must be a YAML mapping with at least the keys `cable` and `loads` "
            "(`cablesim example` prints a complete one)."
        )
    # Overrides recorded in a stored case text apply too, so a result file's case re-parses
    # to exactly what was run.
    apply_overrides(data, [*stored_overrides(text), *(overrides or ())], source)
    if data.get("name") is None:  # absent, or a blank `name:` (YAML null)
        data["name"] = default_name
    try:
        case = Case.model_validate(data)
    except ValidationError as err:
        raise CablesimError(format_validation_error(err, source)) from None
    case._text = _with_overrides(text, overrides)
    return case


def load_case(path: str | Path | None, overrides=None) -> tuple[Case, str]:
    """Read a case file, or the embedded paper example if ``path`` is None.

    ``overrides`` (``KEY=VALUE`` strings) are applied over the file and appended to the
    returned text as a comment, so that a result file records exactly what was run.

    Returns
    -------
    case : Case
    text : str
        The YAML text, stored with every result so that it can be rerun.
    """
    if path is None:
        text = example_text()
        case = parse_case(text, source="(embedded paper example)", default_name="paper-example", overrides=overrides)
        return case, case.text
    p = Path(path)
    try:
        text = p.read_text()
    except FileNotFoundError:
        raise CablesimError(f"Case file {p} does not exist. Check the path.") from None
    except (IsADirectoryError, PermissionError, UnicodeDecodeError) as exc:
        raise CablesimError(f"Case file {p} cannot be read ({exc.__class__.__name__}).") from None
    # A valid case name starts with a letter or digit; derive one from the file stem.
    stem = re.sub(r"[^A-Za-z0-9._-]", "-", p.stem).lstrip("._-") or "case"
    case = parse_case(text, source=str(p), default_name=stem, overrides=overrides)
    return case, case.text


def case_from_dict(data: dict, overrides=None) -> Case:
    """A case from a mapping with the keys of a case file (e.g. built in a notebook).

    Raises
    ------
    CablesimError
        For any invalid field, as for a case file.
    """
    if not isinstance(data, dict):
        raise CablesimError("A case is a mapping with at least the keys `cable` and `loads`.")
    return parse_case(yaml.safe_dump(data, sort_keys=False), source="(case given as a mapping)", overrides=overrides)


OVERRIDES_MARK = "# cablesim --set:"


def _with_overrides(text: str, overrides) -> str:
    if not overrides:
        return text
    return text.rstrip("\n") + "\n" + "".join(f"{OVERRIDES_MARK} {o}\n" for o in overrides)


def stored_overrides(text: str) -> list[str]:
    """The ``--set`` overrides recorded in a stored case text (see :func:`load_case`)."""
    return [line[len(OVERRIDES_MARK):].strip() for line in text.splitlines() if line.startswith(OVERRIDES_MARK)]


def example_text() -> str:
    """The embedded default case (the paper's example), as commented YAML."""
    return resources.files("cablesim").joinpath("data", EXAMPLE_RESOURCE).read_text()


def read_figure(path):
    """The ``figure:`` section of a YAML file (a case file, or a file holding only that section).

    Returns
    -------
    FigureSpec

    Raises
    ------
    CablesimError
        If the file is missing, not YAML, has no ``figure:`` section or an invalid one.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise CablesimError(f"The figure file {path} does not exist. Check the path.") from None
    except (IsADirectoryError, PermissionError, UnicodeDecodeError) as exc:
        raise CablesimError(f"The figure file {path} cannot be read ({exc.__class__.__name__}).") from None
    try:
        data = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError:
        raise CablesimError(f"The figure file {path} is not valid YAML; check its indentation.") from None
    if not isinstance(data, dict) or not isinstance(data.get("figure"), dict):
        raise CablesimError(
            f"The figure file {path} has no figure: section; write one as in a case file "
            "(figure: with kind, title, channels, pair, segments, time_window, labels)."
        )

    class _FigureFile(BaseModel):  # other keys (a whole case file) are ignored
        model_config = ConfigDict(extra="ignore")
        figure: FigureSpec

    try:
        return _FigureFile.model_validate(data).figure
    except ValidationError as err:
        raise CablesimError(format_validation_error(err, f"(figure file) {path}")) from None
