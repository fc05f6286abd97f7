"""Reading case files: strict YAML, ``--set`` overrides, messages that name the field."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

from ..errors import CablesimError
from .model import Case
from .sections import HINTS, FigureSpec

EXAMPLE_RESOURCE = "paper-example.yaml"


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




def format_validation_error(err: ValidationError, source: str) -> str:
    """One readable paragraph for every problem pydantic found in a case file."""
    items = []
    for e in err.errors():
        field = _field_name(e["loc"])
        msg = HINTS.get(e["type"])
        if msg is None:
            msg = e["msg"].removeprefix("Value error, ")
            if "input" in e and e["type"] not in ("model_type",) and not isinstance(e["input"], dict):
                msg += f" (got {e['input']!r})"
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
    if _uses_shorthand(data):
        case.set_text(_expanded_text(text, data, case, overrides))
    else:
        case.set_text(_with_overrides(text, overrides))
    return case


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
    body = yaml.safe_dump(full, sort_keys=False, default_flow_style=None, width=100)
    return f"{EXPANDED_MARK}\n{original}{applied}{body}"


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
