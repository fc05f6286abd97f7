"""Slack (tension-only) segments in motion (docs/theory.md, section 6).

A segment cannot push: ``T = EA max(l - S, 0) / S``. The exact analysis continues through slack
episodes by default (``slack: continue``), locating every slack onset and re-tightening;
``slack: stop`` keeps the old behaviour (the run stops where a segment first goes slack).
"""

from __future__ import annotations

import pytest

from cablesim.analyses.setup import build_equations
from cablesim.case import case_from_dict
from cablesim.errors import CablesimError


# ----------------------------------------------------------------------------------------------
# 1. The setting
# ----------------------------------------------------------------------------------------------
def test_slack_setting_defaults_to_continue_and_reaches_the_equations(paper_case, exact_static, approx_static):
    case = case_from_dict(paper_case)
    assert case.slack == "continue"
    eom = build_equations(case, exact_static)
    assert eom.slack == "continue" and eom.continues_slack
    assert eom.params()[15] == 1
    stop = build_equations(case, exact_static, slack="stop")
    assert not stop.continues_slack and stop.params()[15] == 0
    paper_case["slack"] = "stop"
    case_stop = case_from_dict(paper_case)
    assert build_equations(case_stop, exact_static).slack == "stop"
    # the approximate analysis never continues through slack segments
    assert not build_equations(case, approx_static).continues_slack


def test_slack_setting_is_validated(paper_case):
    paper_case["slack"] = "ignore"
    with pytest.raises(CablesimError, match="slack"):
        case_from_dict(paper_case)


def test_slack_flag_on_the_command_line(tmp_path, paper_case, write_case, invoke_cli):
    """``--slack stop`` is the case's ``slack: stop``: a run that goes slack stops, exit 3."""
    paper_case["loads"]["FL"] = [50 * x for x in paper_case["loads"]["FL"]]
    case = write_case(paper_case)
    r = invoke_cli("history", str(case), "--omega", "2.4", "--duration", "20", "--no-plot", "--slack", "stop",
                   "-o", str(tmp_path / "stop.h5"))
    assert r.returncode == 3, (r.returncode, r.stdout, r.stderr)
    assert "slack" in r.stderr
