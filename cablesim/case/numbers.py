"""Numbers in case files and on the command line: real numbers only, each in a stated range.

A field that holds a number refuses ``true``/``yes`` (YAML booleans), text, and the spellings
YAML 1.1 reads in another base (``020``, ``5:00``; see :mod:`cablesim.case.strict_yaml`), and
checks that the value is finite and inside a physically meaningful range, which the message
states with its unit. The same types check the command-line flags that stand for case-file
fields (``--omega`` for ``history.omega``), so both say the same thing.
"""

from __future__ import annotations

import math
from functools import partial
from typing import Annotated, Any

from pydantic import AfterValidator, BeforeValidator, TypeAdapter, ValidationError

from ..errors import CablesimError
from .strict_yaml import AmbiguousNumber


def plain_number(value: Any) -> Any:
    """Refuse booleans, text and ambiguous spellings where a number belongs."""
    if isinstance(value, bool):
        raise ValueError("must be a number, not true/false (YAML also reads yes, no, on and off as true/false)")
    if isinstance(value, AmbiguousNumber):
        raise ValueError(
            f"is written `{value}`, which YAML 1.1 reads as {value.meaning}; write the number in plain "
            "decimal (no leading zero, no colon)"
        )
    if isinstance(value, (str, bytes)):
        raise ValueError("must be a number, not text; write it without quotes (e.g. 300.0 or 1.0e9)")
    return value


def range_text(lo: float | None, hi: float | None, unit: str, lo_open: bool = False, hi_open: bool = False) -> str:
    """``"from 0.001 to 1e+05 m"``, ``"greater than 0 and at most 1e+07 s"``."""
    u = f" {unit}" if unit else ""
    if lo is not None and hi is not None:
        if not lo_open and not hi_open:
            return f"from {lo:g} to {hi:g}{u}"
        left = f"greater than {lo:g}" if lo_open else f"at least {lo:g}"
        right = f"less than {hi:g}" if hi_open else f"at most {hi:g}"
        return f"{left} and {right}{u}"
    if lo is not None:
        return f"{'greater than' if lo_open else 'at least'} {lo:g}{u}"
    return f"{'less than' if hi_open else 'at most'} {hi:g}{u}"


def _check_range(value, lo, hi, unit, lo_open, hi_open):
    bad = not math.isfinite(value)
    if lo is not None:
        bad |= value <= lo if lo_open else value < lo
    if hi is not None:
        bad |= value >= hi if hi_open else value > hi
    if bad:
        raise ValueError(f"must be {range_text(lo, hi, unit, lo_open, hi_open)}")
    return value


def real(lo: float | None = None, hi: float | None = None, unit: str = "", *, lo_open: bool = False,
         hi_open: bool = False):
    """A float type: a plain finite number in ``[lo, hi]`` (ends open if asked), with its unit."""
    check = partial(_check_range, lo=lo, hi=hi, unit=unit, lo_open=lo_open, hi_open=hi_open)
    return Annotated[float, BeforeValidator(plain_number), AfterValidator(check)]


def integer(lo: int | None = None, hi: int | None = None, unit: str = ""):
    """An int type: a plain whole number in ``[lo, hi]``."""
    check = partial(_check_range, lo=lo, hi=hi, unit=unit, lo_open=False, hi_open=False)
    return Annotated[int, BeforeValidator(plain_number), AfterValidator(check)]


def in_range(values, lo, hi, unit, what="value") -> None:
    """Check every item of a sequence (for tuple-level messages that name the item)."""
    for i, x in enumerate(values):
        if not math.isfinite(x) or not lo <= x <= hi:
            raise ValueError(f"every {what} must be {range_text(lo, hi, unit)}; item {i + 1} is {x:g}")


# Ranges shared by the case file and the command line (SI units).
OMEGA = real(1e-4, 1e4, "rad/s")
DURATION = real(0.0, 1e7, "s", lo_open=True)
OUTPUT_STEP = real(0.0, 1e7, "s", lo_open=True)
#: Size of an initial out-of-plane disturbance of a spatial cable, m.
DISTURBANCE = real(0.0, 1e3, "m")
DAMPING_RATIO = real(0.0, 1.0, "", hi_open=True)
PEAK_VELOCITY = real(0.0, 1e3, "m/s", lo_open=True)
TIME_STEP = real(1e-9, 1e3, "s")
RTOL = real(1e-14, 0.5)
MODE = integer(1, 2000)


def check_flag(kind, value, flag: str, field: str | None = None):
    """Validate a command-line value with a case-file number type; None passes through.

    Raises
    ------
    CablesimError
        ``"--omega must be from 0.0001 to 10000 rad/s (got nan)"``.
    """
    if value is None:
        return None
    try:
        return TypeAdapter(kind).validate_python(value)
    except ValidationError as err:
        msg = err.errors()[0]["msg"].removeprefix("Value error, ")
        if err.errors()[0]["type"] == "finite_number":
            msg = "must be a finite number, not NaN or infinity"
        raise CablesimError(f"{flag} {msg} (got {value!r}).", field=field) from None
