"""Channels: the names users give degrees of freedom, and the columns a result keeps.

``"z1"``, ``"z2"``, ... are the degrees of freedom 1, 2, ... (1-based) in the order
``[x1, x2, x3, x4, ...]`` = (horizontal, vertical) of node 1, then node 2, ...; so ``"z2k"`` is
the vertical displacement (pointing down) of node k. A history may keep only some DOF
(``result.dof``); the column functions map channel names to its columns.
"""

from __future__ import annotations

import numbers
import re

import numpy as np

from .errors import CablesimError

#: ``"z2"``, ``"Z2"``, ``" 2"``: a channel name.
CHANNEL_PATTERN = re.compile(r"^\s*[zZ]?\s*(\d+)\s*$")


def normalise_channel(name) -> str | None:
    """``"z2"``, ``"Z2"``, ``" 2"`` or ``2`` -> ``"z2"``; None if malformed."""
    if isinstance(name, bytes):
        name = name.decode("utf-8", "replace")
    if isinstance(name, bool):
        return None
    if isinstance(name, numbers.Integral):
        return f"z{int(name)}"
    if isinstance(name, str):
        match = CHANNEL_PATTERN.match(name)
        if match is not None:
            return f"z{int(match.group(1))}"
    return None


# --------------------------------------------------------------------------------------------
# Channels
# --------------------------------------------------------------------------------------------


def channel_index(name_or_int, n_dof: int) -> int:
    """Convert a channel name to a 0-based degree-of-freedom index.

    Parameters
    ----------
    name_or_int : str or int
        ``"z2"``, ``"2"`` or ``2``: degree of freedom 2 (1-based), i.e. the vertical
        displacement of node 1.
    n_dof : int
        Number of degrees of freedom of the cable (``2 n``).

    Returns
    -------
    int
        The 0-based index into the DOF axis of the result arrays.

    Raises
    ------
    CablesimError
        If the name is malformed or the channel does not exist.
    """
    hint = f"use z1 to z{n_dof} (z2k is the vertical displacement of node k)"
    if isinstance(name_or_int, bool):
        raise CablesimError(f"Channel {name_or_int!r} is not a channel name; {hint}.")
    if isinstance(name_or_int, numbers.Integral):
        k = int(name_or_int)
    elif isinstance(name_or_int, str):
        match = CHANNEL_PATTERN.match(name_or_int)
        if match is None:
            raise CablesimError(f"Channel name {name_or_int!r} is malformed; {hint}.")
        k = int(match.group(1))
    else:
        raise CablesimError(f"Channel {name_or_int!r} is not a channel name or number; {hint}.")
    if not 1 <= k <= n_dof:
        raise CablesimError(
            f"Channel {name_or_int!r} is out of range for a cable with {n_dof} degrees of freedom; {hint}."
        )
    return k - 1



def channel_description(i: int) -> str:
    """What DOF ``i`` (0-based) is, e.g. ``"node 2, vertical (down +)"``."""
    node, comp = divmod(i, 2)
    return f"node {node + 1}, {'horizontal' if comp == 0 else 'vertical (down +)'}"


def default_channels(n_dof: int) -> list[int]:
    """Default channels (0-based): vertical DOF of every node if n <= 3, else of 3 spread nodes."""
    n = n_dof // 2
    if n <= 3:
        nodes = list(range(1, n + 1))
    else:
        k1 = max(1, int(np.floor((n + 1) / 4 + 0.5)))
        nodes = sorted({k1, (n + 1) // 2, n + 1 - k1})
    return [2 * k - 1 for k in nodes]




# --------------------------------------------------------------------------------------------
# Stored columns: a history may keep only some DOF (``result.dof``)
# --------------------------------------------------------------------------------------------


def cable_dof(result) -> int:
    """Number of degrees of freedom of the cable (``2 n``), even if fewer columns were kept."""
    dofs = result.dof_numbers
    return max(int(np.asarray(result.y0).size), max(dofs) if len(dofs) else 0, int(result.z.shape[1]))


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
    i = channel_index(channel, cable_dof(result))
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
        cols = [dofs.index(i + 1) for i in default_channels(cable_dof(result)) if i + 1 in dofs]
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
    n_dof = cable_dof(result)
    dofs = list(result.dof_numbers)
    want = (1, 2) if n_dof <= 2 else (2, n_dof)
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
    return channel_description(result.dof_numbers[col] - 1)


def parse_channels(spec: str | None, fallback, n_dof: int, flag: str = "--channels", kept=None) -> list[str] | None:
    """The channels of a ``z2,z4`` option (or ``fallback``), each checked against ``n_dof`` and,
    if the result keeps only some channels (``kept``, the case's ``outputs.channels``), against those.

    Raises
    ------
    CablesimError
        For an empty list or a channel the cable does not have.
    """
    names = [c.strip() for c in spec.split(",") if c.strip()] if spec else (list(fallback) if fallback else None)
    if spec is not None and not names:
        raise CablesimError(f"{flag} is empty; give DOF names such as z2,z4.", field="channels")
    for name in names or ():
        try:
            channel_index(name, n_dof)
        except CablesimError as exc:
            raise CablesimError(f"{flag}: {exc}", field="channels") from None
    if kept and names:
        have = [normalise_channel(c) for c in kept]
        missing = [c for c in names if normalise_channel(c) not in have]
        if missing:
            raise CablesimError(
                f"{flag} {','.join(missing)}: the case keeps only {', '.join(have)} (outputs.channels), so "
                "nothing else can be plotted; choose among those, or add the channel to outputs.channels.",
                field="channels",
            )
    return names
