"""Reading case files: strict YAML, ``--set`` overrides, messages that name the field."""

from __future__ import annotations

import re
import stat
from importlib import resources
from pathlib import Path
from typing import Optional

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

from ..errors import CablesimError
from . import strict_yaml
from .model import Case
from .numbers import DURATION, RTOL, TIME_STEP, check_flag
from .placement import placement_lines, read_placements
from .continuation_spec import UNION_TAG
from .sections import HINTS, FigureSpec

EXAMPLE_RESOURCE = "paper-example.yaml"


#: Largest case file read, bytes (a case file is a few kilobytes).
MAX_CASE_BYTES = 1_000_000


def _yaml(text: str, source: str):
    """Parse case-file YAML strictly (:mod:`cablesim.case.strict_yaml`), naming the file."""
    if len(text) > MAX_CASE_BYTES:
        raise CablesimError(
            f"Case file {source} is {len(text)} characters long, more than the {MAX_CASE_BYTES} a case file "
            "may have; give the YAML case file itself (`cablesim example` prints one)."
        )
    if "\0" in text:
        raise CablesimError(f"Case file {source} contains NUL characters, so it is not a text file; give a YAML case file.")
    try:
        return strict_yaml.load(text)
    except strict_yaml.StrictYamlError as exc:
        where = f" at line {exc.line}" if exc.line else ""
        raise CablesimError(f"Case file {source} is refused{where}: {exc}.") from None
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
    except RecursionError:
        raise CablesimError(f"Case file {source} nests too deeply to be a case file.") from None


def _field_name(loc) -> str:
    parts = []
    for p in loc:
        if isinstance(p, str) and p.startswith(UNION_TAG):  # which member of a union: not a key
            continue
        if isinstance(p, int):
            parts.append(f"[{p + 1}]")
        else:
            text = str(p)
            if not text.isprintable():  # a key with a line break must not break the paragraph
                text = text.encode("unicode_escape").decode("ascii")
            parts.append(("." if parts else "") + text)
    return "".join(parts) or "(top level)"




def format_validation_error(err: ValidationError, source: str) -> str:
    """One readable paragraph for every problem pydantic found in a case file."""
    items = []
    for e in err.errors():
        field = _field_name(e["loc"])
        msg = HINTS.get(e["type"])
        if msg is None:
            msg = e["msg"].removeprefix("Value error, ")
            if "input" in e and e["type"] not in ("model_type",) and not isinstance(e["input"], dict):
                got = repr(e["input"])
                msg += f" (got {got if len(got) <= 80 else got[:72] + ' ...' + got[-4:]})"
        # A message that names its own field (the shorthand's checks) goes as it is.
        items.append(f"`{field}` {msg}" if e["loc"] and not msg.startswith("`") else msg)
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
        shown = repr(value) if len(value) <= 60 else repr(value[:40] + " ... " + value[-8:])
        try:
            node[parts[-1]] = strict_yaml.load(value)
        except strict_yaml.StrictYamlError as exc:
            raise CablesimError(f"--set {key}: the value {shown} is refused: {exc}.", field=key.strip()) from None
        except (yaml.YAMLError, RecursionError):
            raise CablesimError(f"--set {key}: the value {shown} is not valid YAML.", field=key.strip()) from None
    return data


def step_flag_overrides(dt: Optional[float], rtol: Optional[float], integrator: Optional[str]) -> list[str]:
    """``--dt`` and ``--rtol`` as ``--set`` overrides of the ``integrator:`` section (recorded with
    the case and checked like it). The flag replaces the case's other kind of step: ``--dt`` clears
    ``rtol`` and ``atol`` (a fixed step), ``--rtol`` clears ``dt`` (error-controlled steps). With
    ``--integrator`` the scheme is set too, so that the section is checked against it."""
    if dt is None and rtol is None:
        return []
    if dt is not None and rtol is not None:
        raise CablesimError("--dt and --rtol exclude each other: --dt fixes the time step, --rtol sets the "
                            "tolerance of error-controlled steps; give one of them.", field="integrator")
    check_flag(TIME_STEP, dt, "--dt", "integrator.dt")
    check_flag(RTOL, rtol, "--rtol", "integrator.rtol")
    sets = [f"integrator.name={integrator}"] if integrator is not None else []
    if dt is not None:
        return sets + [f"integrator.dt={dt!r}", "integrator.rtol=null", "integrator.atol=null"]
    return sets + [f"integrator.rtol={rtol!r}", "integrator.dt=null"]


def check_step_flags(case, dt: Optional[float]) -> None:
    """Refuse ``--dt`` when no scheme is named: cablesim's default for an ordinary cable, dopri5,
    has no fixed step, and the flag would be ignored."""
    if dt is not None and case.integrator.name is None:
        raise CablesimError(
            f"--dt {dt:g} needs a scheme with a fixed step: add --integrator rk4, newmark or generalized-alpha (or "
            "integrator.name in the case file). Without one cablesim chooses dopri5 for an ordinary cable, which "
            "adapts its step to --rtol instead.", field="integrator.dt")


def load_with_steps(path, overrides, dt: Optional[float], rtol: Optional[float], integrator: Optional[str]) -> Case:
    """:func:`load_case` with ``--dt`` or ``--rtol`` set in the ``integrator:`` section
    (:func:`step_flag_overrides`, :func:`check_step_flags`); ``integrator`` the scheme named."""
    case = load_case(path, [*(overrides or ()), *step_flag_overrides(dt, rtol, integrator)])[0]
    check_step_flags(case, dt)
    return case


def sweep_flag_overrides(omega: Optional[str], duration: Optional[float], channels: Optional[str],
                         window: Optional[float] = None) -> list[str]:
    """``--omega``, ``--duration``, ``--channels`` and ``--window`` of ``sweep`` as ``--set``
    overrides (so that they are recorded with the case and checked like it)."""
    sets = []
    if omega is not None:
        parts = omega.split(":") if ":" in omega else None
        try:
            if parts is not None:
                if len(parts) != 3:
                    raise ValueError
                start, stop, num = float(parts[0]), float(parts[1]), int(parts[2])
                sets.append(f"sweep.omega={{start: {start!r}, stop: {stop!r}, num: {num}}}")
            else:
                values = [float(x) for x in omega.split(",") if x.strip()]
                if not values:
                    raise ValueError
                sets.append(f"sweep.omega=[{', '.join(repr(x) for x in values)}]")
        except ValueError:
            raise CablesimError(
                f"--omega {omega!r}: give the frequencies in rad/s as a list W1,W2,... or a grid START:STOP:NUM "
                "(e.g. 0.5:6:56).", field="sweep.omega") from None
    if duration is not None:
        check_flag(DURATION, duration, "--duration", "sweep.duration")
        sets.append(f"sweep.duration={duration!r}")
    if window is not None:
        check_flag(DURATION, window, "--window", "sweep.window")
        sets.append(f"sweep.window={window!r}")
    if channels is not None:
        names = [c.strip() for c in channels.split(",") if c.strip()]
        if not names:
            raise CablesimError("--channels is empty; give DOF names such as z2,z4.", field="sweep.channels")
        sets.append(f"sweep.channels=[{', '.join(names)}]")
    return sets


def sweep_flag_error(exc: CablesimError, duration: Optional[float], window: Optional[float]) -> CablesimError:
    """A case-file error that ``--duration`` or ``--window`` caused, worded for the flags (the
    case file is not at fault when a flag shortened the cap below its window)."""
    found = re.search(r"sweep\.window \(([^ ]+) s\) is longer than sweep\.duration \(([^ ]+) s\)", str(exc))
    if found is None or (duration is None and window is None):
        return exc
    w, d = found.groups()
    cap = f"--duration {d} s" if duration is not None else f"the case's sweep.duration ({d} s)"
    if window is not None:
        return CablesimError(f"--window {w} s is longer than {cap}, the cap on each point's run, of which the window "
                             f"is the final part: give a --window of at most {d} s.", field="sweep.window")
    return CablesimError(f"--duration {d} s is shorter than the case's sweep.window ({w} s), the final part of each "
                         f"point's run used for its amplitude when it does not become steady: give --window too (at "
                         f"most {d} s, e.g. --window {float(d) / 4:g}), or a longer --duration.", field="sweep.window")


def parse_case(text: str, source: str = "<case>", default_name: str = "case", overrides=None,
               record_name: bool = False) -> Case:
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
    record_name : bool
        If the text has no ``name:``, record ``default_name`` in the case's stored text (a case
        file named after its file keeps that name when its stored text is read again).

    Returns
    -------
    Case

    Raises
    ------
    CablesimError
        For malformed YAML or any invalid field.
    """
    data = _yaml(text, source)
    if not isinstance(data, dict):
        raise CablesimError(
            f"Case file {source} must be a YAML mapping with at least the keys `cable` and `loads` "
            "(`cablesim example` prints a complete one)."
        )
    # Overrides recorded in a stored case text apply too, so a result file's case re-parses
    # to exactly what was run.
    apply_overrides(data, [*stored_overrides(text), *(overrides or ())], source)
    named = data.get("name") is not None
    if not named:  # absent, or a blank `name:` (YAML null): the stored name, else the default
        data["name"] = stored_name(text) or default_name
    try:
        case = Case.model_validate(data)
    except ValidationError as err:
        raise CablesimError(format_validation_error(err, source)) from None
    if not case.placements and not overrides:  # a stored text's explicit lists: where its point loads went
        case.set_placements(read_placements(text))
    if _uses_shorthand(data):
        case.set_text(_expanded_text(text, data, case, overrides))
    else:
        stored = text if named or stored_name(text) or not record_name else _with_name(text, case.name)
        case.set_text(_with_overrides(stored, overrides))
    return case


#: Marks the name a case took from its file (it has no ``name:``) in the text stored with
#: results, so that the stored case re-reads under the same name.
NAME_MARK = "# cablesim name (the case file's):"


def _with_name(text: str, name: str) -> str:
    return text.rstrip("\n") + f"\n{NAME_MARK} {name}\n"


def stored_name(text: str) -> str | None:
    """The name recorded in a stored case text for a case that took it from its file."""
    for line in text.splitlines():
        if line.startswith(NAME_MARK):
            return line[len(NAME_MARK):].strip() or None
    return None


#: yaml's safe dumper, compiled (libyaml) when available.
SAFE_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
SHORTHAND = {"cable": ("length", "nodes", "mass_per_length"), "loads": ("gravity", "point")}
EXPANDED_MARK = "# cablesim expanded the shorthand of this case file:"


def _uses_shorthand(data: dict) -> bool:
    return any(isinstance(data.get(sec), dict) and any(k in data[sec] for k in keys) for sec, keys in SHORTHAND.items())


def _expanded_text(text: str, data: dict, case: Case, overrides) -> str:
    """The case text stored with results when the file used the shorthand: the original file as
    comments, then the case with ``cable`` and ``loads`` as the explicit lists they stand for
    (any ``--set`` overrides already applied), so that it re-parses to the same case."""
    original = "".join(f"# | {line}\n" for line in text.rstrip("\n").splitlines())
    applied = "".join(f"# (applied above) --set {o}\n" for o in overrides or ())
    full = {"name": data.get("name"), **data, **case.expanded()}
    # libyaml's emitter when present: the same text, 4x faster for thousands of nodes
    body = yaml.dump(full, Dumper=SAFE_DUMPER, sort_keys=False, default_flow_style=None, width=100)
    return f"{EXPANDED_MARK}\n{original}{applied}{placement_lines(case.placements)}{body}"


def name_from_stem(stem: str) -> str:
    """A valid case name (a letter or digit first, then letters, digits, '.', '_', '-') made from
    a file's stem: ``"my run"`` -> ``"my-run"``."""
    return re.sub(r"[^A-Za-z0-9._-]", "-", stem).lstrip("._-") or "case"


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
        case = parse_case(text, source="(embedded paper example)", default_name="paper-example", overrides=overrides,
                          record_name=True)
        return case, case.text
    p = Path(path)
    text = read_text_file(p, "Case file", MAX_CASE_BYTES)
    case = parse_case(text, source=str(p), default_name=name_from_stem(p.stem), overrides=overrides, record_name=True)
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
    return parse_case(yaml.safe_dump(_plain(data), sort_keys=False), source="(case given as a mapping)",
                      overrides=overrides)


def _plain(value):
    """``value`` with numpy numbers and arrays (as a notebook computes them) made Python ones."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    tolist = getattr(value, "tolist", None)  # numpy scalars and arrays, without importing numpy here
    return _plain(tolist()) if callable(tolist) and not isinstance(value, (str, bytes)) else value


OVERRIDES_MARK = "# cablesim --set:"


def _with_overrides(text: str, overrides) -> str:
    if not overrides:
        return text
    return text.rstrip("\n") + "\n" + "".join(f"{OVERRIDES_MARK} {o}\n" for o in overrides)


def stored_overrides(text: str) -> list[str]:
    """The ``--set`` overrides recorded in a stored case text (see :func:`load_case`)."""
    return [line[len(OVERRIDES_MARK):].strip() for line in text.splitlines() if line.startswith(OVERRIDES_MARK)]


def read_text_file(path: Path, what: str, limit: int) -> str:
    """The text of a small regular file, or a message saying why it cannot be read.

    Devices (``/dev/zero``), pipes and folders are refused before anything is read, and at most
    ``limit`` bytes are read.
    """
    try:
        st = path.stat()
    except FileNotFoundError:
        raise CablesimError(f"{what} {path} does not exist. Check the path.") from None
    except OSError as exc:
        raise CablesimError(f"{what} {path} cannot be read ({exc.strerror or exc.__class__.__name__}).") from None
    if stat.S_ISDIR(st.st_mode):
        raise CablesimError(f"{what} {path} cannot be read (IsADirectoryError): it is a folder; give a YAML file.")
    if not stat.S_ISREG(st.st_mode):
        raise CablesimError(f"{what} {path} cannot be read: it is not a regular file (a device or a pipe); give a YAML file.")
    if st.st_size > limit:
        raise CablesimError(f"{what} {path} is {st.st_size} bytes, more than the {limit} a case file may have; give the YAML file itself.")
    try:
        with open(path, "rb") as f:
            raw = f.read(limit + 1)
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        raise CablesimError(f"{what} {path} cannot be read (UnicodeDecodeError): it is not UTF-8 text; give a YAML file.") from None
    except OSError as exc:
        raise CablesimError(f"{what} {path} cannot be read ({exc.strerror or exc.__class__.__name__}).") from None


def example_cases() -> dict[str, str]:
    """The case files shipped with cablesim: name -> what it is (the first line of its comments)."""
    out = {}
    for item in sorted(resources.files("cablesim").joinpath("data").iterdir(), key=lambda f: f.name):
        if item.name.endswith(".yaml"):
            first = item.read_text().splitlines()[0].lstrip("# ").removeprefix("cablesim case file: ")
            out[item.name.removesuffix(".yaml")] = first
    return out


def example_text(name: str = EXAMPLE_RESOURCE.removesuffix(".yaml")) -> str:
    """A case shipped with cablesim, as commented YAML: by default the paper's example (the
    embedded default case, with every section); :func:`example_cases` lists the others."""
    cases = example_cases()
    if name not in cases:
        raise CablesimError(f"There is no shipped case named {name!r}; the shipped cases are {', '.join(cases)} "
                            "(`cablesim example --list` says what each is).", field="example")
    return resources.files("cablesim").joinpath("data", f"{name}.yaml").read_text()


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
    text = read_text_file(path, "The figure file", MAX_CASE_BYTES)
    try:
        data = strict_yaml.load(text)
    except strict_yaml.StrictYamlError as exc:
        raise CablesimError(f"The figure file {path} is refused: {exc}.") from None
    except (yaml.YAMLError, RecursionError):
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
