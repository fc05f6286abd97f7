"""Case files: YAML in, a frozen and validated :class:`Case` out.

A case file describes one cable, its loads, the analysis and the damping (SI units throughout:
m, N, kg, s, rad/s). Unknown keys are errors, so a misspelt key is never silently ignored.
:func:`load_case` turns every problem into a :class:`~cablesim.errors.CablesimError` whose
message names the field and says what to do.
"""

from .files import (
    EXAMPLE_RESOURCE,
    OVERRIDES_MARK,
    apply_overrides,
    case_from_dict,
    example_text,
    format_validation_error,
    load_case,
    parse_case,
    read_figure,
    stored_overrides,
)
from .model import Case
from .charts import BackboneSpec
from .continuation_spec import ContinuationSpec, LociRange, ParameterRange
from .integrator_spec import IntegratorSpec
from .sections import (
    FIGURE_KINDS,
    CableSpec,
    DampingSpec,
    FigureSpec,
    FreeVibrationSpec,
    HistorySpec,
    LoadsSpec,
    ModalSpec,
    OmegaGrid,
    OutputsSpec,
    SweepSpec,
)

__all__ = [
    "EXAMPLE_RESOURCE", "FIGURE_KINDS", "OVERRIDES_MARK", "BackboneSpec", "CableSpec", "Case", "ContinuationSpec", "DampingSpec",
    "FigureSpec", "FreeVibrationSpec", "HistorySpec", "IntegratorSpec", "LoadsSpec", "LociRange", "ModalSpec", "OmegaGrid", "OutputsSpec",
    "ParameterRange", "SweepSpec", "apply_overrides", "case_from_dict", "example_text", "format_validation_error",
    "load_case", "parse_case", "read_figure", "stored_overrides",
]
