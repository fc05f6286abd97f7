"""Strict YAML for case files: what a person meant, or a refusal that says where.

PyYAML follows YAML 1.1, which reads several spellings in ways nobody writing a case file
means: ``020`` is the octal number 16, ``5:00`` the base-60 number 300, ``0x1F`` hexadecimal,
and a key written twice silently keeps its last value (a second ``loads:`` section replaces the
first). This loader

- refuses a key that appears twice in the same mapping, naming both lines;
- keeps octal, base-60, hexadecimal and binary spellings as text (:class:`AmbiguousNumber`), so
  that a field expecting a number refuses them and says how YAML 1.1 would have read them;
- reads ``1.0e9`` (a string to YAML 1.1) as the float it looks like;
- limits nesting depth, alias use (no "billion laughs") and the expanded size of the document;
- refuses the explicit tags that make values no field takes (``!!set``, ``!!omap``, ``!!pairs``,
  ``!!binary``, ``!!timestamp``) and whole numbers of more digits than any double holds.

Every refusal is a :class:`StrictYamlError` carrying the line; :mod:`cablesim.case.files` turns
it into a message naming the file.
"""

from __future__ import annotations

import re

import yaml

#: Deepest nesting of mappings and lists (a case file needs four).
MAX_DEPTH = 32
#: Most aliases (``*name``) in one document.
MAX_ALIASES = 100
#: Most values in the document with every alias expanded.
MAX_NODES = 200_000

_INT = re.compile(r"^[-+]?(?:0|[1-9][0-9_]*)$")
_FLOAT = re.compile(
    r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
    |[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?
    |[-+]?\.(?:inf|Inf|INF)
    |\.(?:nan|NaN|NAN))$""",
    re.X,
)
_AMBIGUOUS = re.compile(
    r"""^[-+]?(?:0[0-9_]+
    |0[xX][0-9a-fA-F_]+
    |0[bB][01_]+
    |0[oO][0-7_]+
    |[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?)$""",
    re.X,
)
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE|yes|Yes|YES|no|No|NO|on|On|ON|off|Off|OFF)$")
_AMBIGUOUS_TAG = "tag:cablesim,2024:ambiguous-number"
_NUMERIC_TAGS = ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float", "tag:yaml.org,2002:bool")


class StrictYamlError(Exception):
    """A case file YAML refuses to read as written (``line`` is 1-based, or None)."""

    def __init__(self, message: str, line: int | None = None):
        super().__init__(message)
        self.line = line


class AmbiguousNumber(str):
    """Text that YAML 1.1 would have read as a number in a surprising base.

    ``meaning`` says how (``"the octal number 16"``); a number field refuses it with that.
    """

    meaning: str = ""


def _meaning(text: str) -> str:
    s = text.replace("_", "")
    sign = -1 if s.startswith("-") else 1
    body = s.lstrip("+-")
    if ":" in body:
        value = 0.0
        for part in body.split(":"):
            value = value * 60 + float(part)
        value *= sign
        return f"the base-60 (sexagesimal) number {value:g}"
    low = body.lower()
    for prefix, base, word in (("0x", 16, "hexadecimal"), ("0b", 2, "binary"), ("0o", 8, "octal")):
        if low.startswith(prefix):
            return f"the {word} number {sign * int(body[2:], base)}"
    try:
        return f"the octal number {sign * int(body, 8)}"
    except ValueError:
        return "an octal number (and not a valid one)"


class StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader with the rules in the module docstring."""

    def __init__(self, stream):
        super().__init__(stream)
        self._depth = 0
        self._aliases = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise StrictYamlError(
                    f"it uses more than {MAX_ALIASES} aliases (*name); write the values out", _line(self.peek_event())
                )
            return super().compose_node(parent, index)
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise StrictYamlError(
                    f"it nests lists and mappings more than {MAX_DEPTH} deep; a case file needs four levels",
                    _line(self.peek_event()),
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_document(self, node):
        _check_tree(node)
        return super().construct_document(node)


def _line(obj) -> int | None:
    mark = getattr(obj, "start_mark", None)
    return None if mark is None else mark.line + 1


def _check_tree(root) -> None:
    """Duplicate keys (with their lines), cycles and the expanded size of the document."""
    sizes: dict[int, int] = {}
    active: set[int] = set()

    def visit(node, path: str) -> int:
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in active:
            raise StrictYamlError(f"`{path or '(top level)'}` contains itself through an alias", _line(node))
        active.add(key)
        total = 1
        if isinstance(node, yaml.MappingNode):
            seen: dict = {}
            for k, v in node.value:
                name = k.value if isinstance(k, yaml.ScalarNode) else None
                if name is not None and not name.isprintable():
                    name = name.encode("unicode_escape").decode("ascii")
                if name is not None and name != "<<":
                    if name in seen:
                        where = f"in `{path}`" if path else "at the top level"
                        raise StrictYamlError(
                            f"the key `{name}` appears twice {where} (lines {seen[name]} and {_line(k)}); "
                            "YAML would silently keep only the last one. Keep one of them",
                            _line(k),
                        )
                    seen[name] = _line(k)
                total += visit(k, path) + visit(v, f"{path}.{name}" if path else str(name))
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                total += visit(v, f"{path}[{i + 1}]")
        active.discard(key)
        sizes[key] = total
        if total > MAX_NODES:
            raise StrictYamlError(
                f"it expands to more than {MAX_NODES} values (aliases repeat whole sections); write the values out",
                _line(node),
            )
        return total

    visit(root, "")


def _construct_ambiguous(loader, node):
    value = AmbiguousNumber(loader.construct_scalar(node))
    value.meaning = _meaning(str(value))
    return value


#: Most digits of a whole number (a double holds up to about 1.8e308; Python refuses to read
#: integers of more than 4300 digits).
MAX_DIGITS = 310
#: Explicit YAML tags whose values no case-file field takes (a `!!set` would become a list).
_REFUSED_TAGS = {"set": "a set", "omap": "an ordered mapping", "pairs": "a list of pairs",
                 "binary": "binary data", "timestamp": "a date"}


def _construct_int(loader, node):
    digits = sum(ch.isdigit() for ch in node.value)
    if digits > MAX_DIGITS:
        raise StrictYamlError(f"a whole number of {digits} digits is written (`{node.value[:12]}...`), beyond any value a "
                              "case takes (a double holds up to about 1.8e308); write a number in range, e.g. 1.0e9",
                              _line(node))
    return yaml.SafeLoader.construct_yaml_int(loader, node)


def _refuse_tag(word: str):
    def construct(loader, node):
        raise StrictYamlError(f"`{node.tag.replace('tag:yaml.org,2002:', '!!')}` makes {word}, which no case-file field "
                              "takes; write a plain value or list without the tag", _line(node))
    return construct


def _install_resolvers() -> None:
    # Drop YAML 1.1's number and boolean resolvers, then add the strict ones.
    StrictLoader.yaml_implicit_resolvers = {
        ch: [(tag, rx) for tag, rx in resolvers if tag not in _NUMERIC_TAGS]
        for ch, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
    }
    StrictLoader.add_implicit_resolver("tag:yaml.org,2002:bool", _BOOL, list("tTfFyYnNoO"))
    StrictLoader.add_implicit_resolver(_AMBIGUOUS_TAG, _AMBIGUOUS, list("-+0123456789"))
    StrictLoader.add_implicit_resolver("tag:yaml.org,2002:int", _INT, list("-+0123456789"))
    StrictLoader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT, list("-+0123456789."))
    StrictLoader.add_constructor(_AMBIGUOUS_TAG, _construct_ambiguous)
    StrictLoader.add_constructor("tag:yaml.org,2002:int", _construct_int)
    for name, word in _REFUSED_TAGS.items():
        StrictLoader.add_constructor(f"tag:yaml.org,2002:{name}", _refuse_tag(word))


_install_resolvers()


def load(text: str):
    """Parse YAML text with :class:`StrictLoader`.

    Raises
    ------
    StrictYamlError
        For the refusals above.
    yaml.YAMLError
        For malformed YAML.
    """
    return yaml.load(text, Loader=StrictLoader)
