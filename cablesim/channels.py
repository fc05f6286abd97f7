"""Channels: the names users give degrees of freedom, and the columns a result keeps.

``"z1"``, ``"z2"``, ... are the degrees of freedom 1, 2, ... (1-based) in the order
``[x1, x2, x3, x4, ...]`` = (horizontal, vertical) of node 1, then node 2, ...; so ``"z2k"`` is
the vertical displacement (pointing down) of node k. The same by node and direction:
``"node20.v"`` is node 20 vertical (down +, = ``z40``) and ``"node20.h"`` horizontal (= ``z39``).
A spatial cable has three components per node, ``(x, v, w)`` (``w`` horizontal, out of the
vertical plane through A and B), so ``z3k`` is node k's ``w`` and ``"node20.w"`` stands for
``z60``; every function takes the components per node as ``dim`` (2 unless given).
Every place that takes channel names (case file, ``--channels``, plots, sweeps) reads them here
and works with the ``z`` names. A history may keep only some DOF (``result.dof``); the column
functions map channel names to its columns.
"""

from __future__ import annotations

import numbers
import re

import numpy as np

from .errors import CablesimError

#: ``"z2"``, ``"Z2"``, ``" 2"``: a channel name.
CHANNEL_PATTERN = re.compile(r"^\s*[zZ]?\s*(\d+)\s*$")
#: ``"node20.v"``, ``"Node 20.H"``: a channel by node and direction.
NODE_CHANNEL_PATTERN = re.compile(r"^\s*node\s*(\d+)\s*\.\s*(\w*)\s*$", re.IGNORECASE)
#: Directions of a node channel and the DOF of node k they stand for (dim (k - 1) + 1 + offset).
NODE_DIRECTIONS = {"h": 0, "v": 1, "w": 2}
#: The directions in words.
DIRECTION_WORDS = ("horizontal", "vertical (down +)", "out of plane")


def _parse(name, dim: int = 2) -> tuple[int, int | None, str | None]:
    """``(DOF number, node, problem)`` of a channel name; ``problem`` says what is wrong."""
    if isinstance(name, bytes):
        name = name.decode("utf-8", "replace")
    if isinstance(name, bool) or not isinstance(name, (str, numbers.Integral)):
        return 0, None, "is not a channel name"
    if isinstance(name, numbers.Integral):
        return int(name), None, None
    match = CHANNEL_PATTERN.match(name)
    if match is not None:
        return int(match.group(1)), None, None
    match = NODE_CHANNEL_PATTERN.match(name)
    if match is None:
        return 0, None, "is malformed"
    node, direction = int(match.group(1)), match.group(2).lower()
    if direction not in NODE_DIRECTIONS or NODE_DIRECTIONS[direction] >= dim:
        w = ", .w (out of plane)" if dim == 3 else ""
        extra = " (.w is for spatial cases: spatial: true)" if direction == "w" else ""
        return 0, node, (f"has direction {match.group(2)!r}{extra}; a node channel ends in .h (horizontal){w} or .v "
                         f"(vertical, down +), e.g. node{node}.v")
    if node < 1:
        return 0, node, "names node 0, but nodes are numbered from 1 (next to support A)"
    return dim * (node - 1) + 1 + NODE_DIRECTIONS[direction], node, None


def normalise_channel(name, dim: int = 2) -> str | None:
    """``"z2"``, ``"Z2"``, ``" 2"``, ``2`` or ``"node1.v"`` -> ``"z2"``; None if malformed."""
    k, _, problem = _parse(name, dim)
    return None if problem else f"z{k}"


def node_channel_name(i: int, dim: int = 2) -> str:
    """The node-and-direction name of DOF ``i`` (0-based), e.g. ``"node20.v"`` for 39."""
    node, comp = divmod(i, dim)
    return f"node{node + 1}.{'hvw'[comp]}"


# --------------------------------------------------------------------------------------------
# Channels
# --------------------------------------------------------------------------------------------


def channel_index(name_or_int, n_dof: int, dim: int = 2) -> int:
    """Convert a channel name to a 0-based degree-of-freedom index.

    Parameters
    ----------
    name_or_int : str or int
        ``"z2"``, ``"2"``, ``2`` or ``"node1.v"``: degree of freedom 2 (1-based), i.e. the
        vertical displacement of node 1 (``"node1.h"``: its horizontal one, z1).
    n_dof : int
        Number of degrees of freedom of the cable (``dim n``).
    dim : int
        Components per node (2 planar, 3 spatial).

    Returns
    -------
    int
        The 0-based index into the DOF axis of the result arrays.

    Raises
    ------
    CablesimError
        If the name is malformed or the channel does not exist.
    """
    n = n_dof // dim
    hint = f"use z1 to z{n_dof} (z{dim}k{'-1' if dim == 3 else ''} is the vertical displacement of node k)"
    if isinstance(name_or_int, str) and name_or_int.strip().lower().startswith("node"):
        last = "w" if dim == 3 else "v"
        hint = (f"use node1.h to node{n}.{last} (h horizontal, v vertical, down +{', w out of plane' if dim == 3 else ''}) "
                f"or z1 to z{n_dof}")
    k, node, problem = _parse(name_or_int, dim)
    if problem:
        raise CablesimError(f"Channel {name_or_int!r} {problem}; {hint}.")
    if node is not None and node > n:
        raise CablesimError(f"Channel {name_or_int!r} names node {node}, but this cable has n = {n} interior "
                            f"nodes; {hint}.")
    if not 1 <= k <= n_dof:
        raise CablesimError(
            f"Channel {name_or_int!r} is out of range for a cable with {n_dof} degrees of freedom; {hint}."
        )
    return k - 1


def channel_description(i: int, dim: int = 2) -> str:
    """What DOF ``i`` (0-based) is, e.g. ``"node 2, vertical (down +)"``."""
    node, comp = divmod(i, dim)
    return f"node {node + 1}, {DIRECTION_WORDS[comp]}"


def default_channels(n_dof: int, dim: int = 2) -> list[int]:
    """Default channels (0-based): vertical DOF of every node if n <= 3, else of 3 spread nodes
    (and, for a spatial cable, their out-of-plane DOF too)."""
    n = n_dof // dim
    if n <= 3:
        nodes = list(range(1, n + 1))
    else:
        k1 = max(1, int(np.floor((n + 1) / 4 + 0.5)))
        nodes = sorted({k1, (n + 1) // 2, n + 1 - k1})
    if dim == 3:
        return [i for k in nodes for i in (3 * k - 2, 3 * k - 1)]
    return [2 * k - 1 for k in nodes]




# --------------------------------------------------------------------------------------------
# Stored columns: a history may keep only some DOF (``result.dof``)
# --------------------------------------------------------------------------------------------


def cable_dof(result) -> int:
    """Number of degrees of freedom of the cable (``dim n``), even if fewer columns were kept."""
    dofs = result.dof_numbers
    return max(int(np.asarray(result.y0).size), max(dofs) if len(dofs) else 0, int(result.z.shape[1]))


def components(result) -> int:
    """Components per node of a result's cable (2 planar, 3 spatial): from its equilibrium and
    tensions (``dim n`` coordinates for ``n + 1`` segments)."""
    n = int(np.asarray(result.T0).size) - 1
    return int(np.asarray(result.y0).size) // n if n > 0 else 2


def stored_names(result) -> str:
    """The stored channels, for messages: ``"z2, z4"``."""
    return ", ".join(f"z{d}" for d in result.dof_numbers)


def column_of(result, channel) -> int:
    """Column of ``result.z`` (``v``, ``zc``, ``ze``) holding a channel.

    Raises
    ------
    CablesimError
        If the name is malformed or out of range for the cable, or the history did not keep
        that channel (the message names the stored ones).
    """
    i = channel_index(channel, cable_dof(result), components(result))
    dofs = list(result.dof_numbers)
    if i + 1 not in dofs:
        raise CablesimError(
            f"Channel {channel!r} (z{i + 1}) was not stored in this history: it kept only "
            f"{stored_names(result)} (outputs.channels). Choose among those, or rerun with the channel "
            "listed in outputs.channels."
        )
    return dofs.index(i + 1)


def resolve_columns(result, channels=None) -> list[int]:
    """Columns of ``result.z`` for the channels; default: the default channels that were stored.

    The default is the vertical DOF of every node (n <= 3) or of three spread nodes, among the
    stored channels; if none of those was kept, every stored channel.
    """
    if channels is None:
        dofs = list(result.dof_numbers)
        cols = [dofs.index(i + 1) for i in default_channels(cable_dof(result), components(result)) if i + 1 in dofs]
        return cols or list(range(len(dofs)))
    if isinstance(channels, (str, numbers.Integral)):
        channels = [channels]
    out: list[int] = []
    for c in channels:
        col = column_of(result, c)
        if col not in out:
            out.append(col)
    if not out:
        raise CablesimError(f"No channels were chosen to plot; name at least one of {stored_names(result)}.")
    return out


def default_pair(result):
    """Default Lissajous pair (columns): vertical DOF of the first and last node if stored.

    Otherwise the first two default (or stored) columns; None if fewer than two were kept.
    """
    n_dof, dim = cable_dof(result), components(result)
    dofs = list(result.dof_numbers)
    want = (1, 2) if n_dof <= dim else (2, n_dof - dim + 2)
    if all(d in dofs for d in want):
        return dofs.index(want[0]), dofs.index(want[1])
    cols = resolve_columns(result)
    if len(cols) < 2:
        cols = list(range(len(dofs)))
    return (cols[0], cols[1]) if len(cols) >= 2 else None


def column_name(result, col: int) -> str:
    """Channel name of a stored column, e.g. ``"z4"``."""
    return f"z{result.dof_numbers[col]}"


def column_description(result, col: int) -> str:
    """What a stored column is, e.g. ``"node 2, vertical (down +)"``."""
    return channel_description(result.dof_numbers[col] - 1, components(result))


def parse_channels(spec: str | None, fallback, n_dof: int, flag: str = "--channels", kept=None,
                   dim: int = 2) -> list[str] | None:
    """The channels of a ``z2,z4`` option (or ``fallback``), each checked against ``n_dof`` and,
    if the result keeps only some channels (``kept``, the case's ``outputs.channels``), against those.

    Raises
    ------
    CablesimError
        For an empty list or a channel the cable does not have.
    """
    names = [c.strip() for c in spec.split(",") if c.strip()] if spec else (list(fallback) if fallback else None)
    if spec is not None and not names:
        raise CablesimError(f"{flag} is empty; give DOF names such as z2,z4 or node20.v.", field="channels")
    for name in names or ():
        try:
            channel_index(name, n_dof, dim)
        except CablesimError as exc:
            raise CablesimError(f"{flag}: {exc}", field="channels") from None
    if kept and names:
        have = [normalise_channel(c, dim) for c in kept]
        missing = [c for c in names if normalise_channel(c, dim) not in have]
        if missing:
            raise CablesimError(
                f"{flag} {','.join(missing)}: the case keeps only {', '.join(have)} (outputs.channels), so "
                "nothing else can be plotted; choose among those, or add the channel to outputs.channels.",
                field="channels",
            )
    return names
