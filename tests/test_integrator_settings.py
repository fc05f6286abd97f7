"""One table of integrator settings: the case schema, the factory, the override check and the
stress harness read it, and nothing downstream branches on a scheme's name or type."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
from pydantic import ValidationError

from cablesim.case import IntegratorSpec, parse_case
from cablesim.dynamics.integrators import INTEGRATORS
from cablesim.dynamics.integrators.settings import (IMPLICIT_ATOL_PER_CHORD, IMPLICIT_RTOL, SCHEMES, default_scheme,
                                                     ignored_keys, make)
from cablesim.names import INTEGRATOR_KEYS, INTEGRATOR_SETTINGS

ROOT = Path(__file__).resolve().parents[1] / "cablesim"
EXAMPLE = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"


def test_every_scheme_of_the_table_takes_its_keys():
    assert tuple(SCHEMES) == tuple(INTEGRATORS) == tuple(INTEGRATOR_SETTINGS)
    for name, row in SCHEMES.items():
        fields = {f.name for f in dataclasses.fields(row.cls)}
        assert set(row.keys) <= fields, (name, row.keys, fields)
        assert row.cls.name == name
    assert set(INTEGRATOR_KEYS) == {f for f in IntegratorSpec.model_fields if f != "name"}


@pytest.mark.parametrize("name", sorted(INTEGRATOR_SETTINGS))
def test_the_case_schema_refuses_exactly_the_keys_a_scheme_does_not_take(name):
    for key in INTEGRATOR_KEYS:
        value = {"dt": 0.01, "rtol": 1e-7, "atol": 1e-9, "rho_inf": 0.5}[key]
        if key in INTEGRATOR_SETTINGS[name]:
            assert IntegratorSpec(name=name, **{key: value}).settings() == {key: value}
        else:
            with pytest.raises(ValidationError, match=f"integrator.{key} does not apply to {name}"):
                IntegratorSpec(name=name, **{key: value})
            assert ignored_keys(name, {key: value}) == [key]


def test_the_factory_fills_in_the_defaults_of_the_table():
    from cablesim.analyses.setup import build_equations
    from cablesim.analyses.static import run_static

    case = parse_case(EXAMPLE.read_text())
    eom = build_equations(case, run_static(case), omega=2.4)
    assert default_scheme(eom, 2.4) == "dopri5"
    d = make(None, eom, 2.4)
    assert d.name == "dopri5" and d.rtol == 1e-8 and d.atol == pytest.approx(1e-10 * eom.cable.chord_length)
    period = 2.0 * 3.141592653589793 / 2.4
    rk = make("rk4", eom, 2.4)
    assert rk.fixed_step and period / rk.dt == pytest.approx(round(period / rk.dt), rel=1e-9)  # divides the period
    assert rk.dt <= period / 100 * (1 + 1e-12)
    for name in ("newmark", "generalized-alpha"):  # error-controlled by default; dt fixes the step
        integ = make(name, eom, 2.4)
        assert not integ.fixed_step and integ.rtol == IMPLICIT_RTOL
        assert integ.atol == pytest.approx(IMPLICIT_ATOL_PER_CHORD * eom.cable.chord_length)
        # an atol not given follows rtol: a fixed one held a taut stay's steps whatever rtol asked
        loose = make(name, eom, 2.4, {"rtol": 100 * IMPLICIT_RTOL})
        assert loose.atol == pytest.approx(100 * IMPLICIT_ATOL_PER_CHORD * eom.cable.chord_length)
        assert integ.omega_ref == 2.4 and period / integ.dt_max == pytest.approx(round(period / integ.dt_max), rel=1e-9)
        fixed = make(name, eom, 2.4, {"dt": period / 300})
        assert fixed.fixed_step and fixed.dt == period / 300 and "rtol" not in fixed.settings()
        with pytest.raises(ValueError, match="exclude each other"):
            make(name, eom, 2.4, {"dt": 0.01, "rtol": 1e-6})
    assert make("generalized-alpha", eom, 2.4, {"rho_inf": 0.3}).rho_inf == 0.3
    with pytest.raises(ValueError, match="takes dt"):
        make("rk4", eom, 2.4, {"rtol": 1e-6})


#: Branching on a scheme: ``isinstance(x, DOPRI5)``, ``.name == "rk4"``, ``kind == "newmark"``.
BRANCH = re.compile(r"isinstance\([^)]*\b(RK4|DOPRI5|Newmark|GeneralizedAlpha)\b"
                    r"|\b(name|kind)\s*(==|!=|in)\s*\(?\s*[\"'](rk4|dopri5|newmark|generalized-alpha)[\"']")


def test_nothing_downstream_branches_on_a_scheme():
    found = []
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith("dynamics/integrators/"):
            continue
        for i, line in enumerate(path.read_text().splitlines(), 1):
            if BRANCH.search(line.split("#", 1)[0]):
                found.append(f"{rel}:{i}: {line.strip()}")
    assert not found, "\n".join(found)
