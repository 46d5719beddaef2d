"""design.checker_power: read at its key, and the margin only ever costs more (judge.margin)."""

from __future__ import annotations

from pathlib import Path

import pytest

from rockfall_design.errors import ProjectError
from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.optimiser import optimise
from rockfall_design.project import load_project_text

SMALL_DESIGN = Path(__file__).resolve().parents[1] / "data" / "design_small.yaml"


def _small(power: str | None):
    text = SMALL_DESIGN.read_text(encoding="utf-8")
    if power is not None:
        text = text.replace("  max_measures: 1\n", f"  max_measures: 1\n  checker_power: {power}\n")
    return load_project_text(text, "small.yaml", base_dir=SMALL_DESIGN.parent)


@pytest.mark.parametrize(("power", "read"), [(None, 0.9), ("null", None), ("0.95", 0.95)])
def test_checker_power_is_read(registry, power, read):
    assert resolve_design(_small(power), registry).checker_power == read


@pytest.mark.parametrize("power", ["1.0", "0.3", "high"])
def test_a_checker_power_out_of_range_is_an_error_at_its_key(power):
    with pytest.raises(ProjectError, match=r"small.yaml:\d+: design.checker_power"):
        _small(power)


@pytest.mark.slow  # three optimisations of the small design: CI runs it with -m slow
@pytest.mark.parametrize("seed", [5, 9])
def test_the_margin_only_ever_costs_more(registry, seed):
    """Without the margin (null) a design is admitted as the bounds alone say; with it, a
    look admits only what it would admit without (on the same rocks), so the choice is
    never cheaper, nor with a higher power than with a lower one. (Not a law: the search
    next to a chosen ditch walks from different places; held at two seeds here.)"""
    costs = []
    for power in ("null", "0.8", "0.95"):
        res = optimise(_small(power), registry, seed=seed)
        assert res.best is not None
        costs.append(res.best.cost)
        power_recorded = res.best.fresh_looks.get("checker_power")
        assert power_recorded == (None if power == "null" else float(power))
    assert costs == sorted(costs)


def test_design_yaml_carries_the_projects_confidence_and_the_margin(tmp_path, capsys):
    """design.yaml's safety.confidence is the project's (95 %), not the deciding look's
    higher one: a checker's `check design.yaml` is one look, and the margin the design was
    admitted with is for a check at the project's confidence, which the file states."""
    import yaml

    from rockfall_design.cli.program import main

    assert main(["optimise", str(SMALL_DESIGN), "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    text = (tmp_path / "design.yaml").read_text(encoding="utf-8")
    assert yaml.safe_load(text)["safety"]["confidence"] == 0.95
    assert "# margin: admitted only as a design that a check of" in text
    assert "confirms with 95 % confidence at least 90 % of the time" in text
