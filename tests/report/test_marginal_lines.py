"""The line for a marginal or undecided cheaper design: the terminal panel, the report and
design.yaml (report.listed)."""

from pathlib import Path
from types import SimpleNamespace

from rockfall_design.judge.looks import LookCheck, LookValues
from rockfall_design.report.listed import values_phrase as _marginal_values


def _design(bound, optimistic, value=0.66):
    check = LookCheck("fence", "reach_factor", value, bound, optimistic, 1.0, "-")
    return SimpleNamespace(values=LookValues(4603, 0.99, [check], None), reason="")


def test_both_ends_read_as_a_range():
    assert "reach_factor 0.95 (0.90 to 1.04)" in _marginal_values(_design(0.90, 1.04, 0.95))


def test_one_end_is_not_shown_as_a_range_of_one_value():
    # Too few rocks at a ditch for an upper bound of its p95 reach: only the
    # optimistic end exists. It once read "0.66 (1.12 to 1.12)".
    line = _marginal_values(_design(None, 1.12))
    assert "1.12 to 1.12" not in line
    assert "reach_factor 0.66 (at best 1.12; too few rocks to bound it the other way)" in line
    assert "(with confidence 0.90)" in _marginal_values(_design(0.90, None, 0.95))
    assert "reach_factor 0.66, target" in _marginal_values(_design(None, None))


def _entry(**kw):
    """A listed design as report.listed reads it (the attributes of optimiser's Listed)."""
    check = LookCheck("fence", "height_factor", 1.02, 0.97, 1.08, 1.0, "-")
    fields = {"family": "fence", "labels": ["fence RX-100 3.5 m at x = 92 m"],
              "cost": 68_000.0, "values": LookValues(200_000, 0.993, [check], None),
              "rocks_to_decide": 512_345, "decided": True, "short_of_margin": False,
              "margin_undecided": False, "reason": "", "beyond_rocks": None}
    return SimpleNamespace(**{**fields, **kw})


def test_a_listed_design_says_the_rocks_that_would_decide_it():
    from rockfall_design.report.listed import listed_lines, what_decides

    (line,) = listed_lines([_entry()], "EUR")
    assert line.startswith("- Marginal, cheaper: fence 68,000 EUR: fence RX-100")
    assert "height_factor 1.02 (0.97 to 1.08), target 1.00" in line
    # the estimate, and a budget to type rounded up to two figures
    assert line.endswith("about 512,345 rocks would decide it (--max-rocks 520000)")
    assert "sits on the target" in what_decides(_entry(rocks_to_decide=None))
    assert "checker_power" in what_decides(_entry(short_of_margin=True))
    assert "Not decided" in listed_lines([_entry(decided=False)])[0]


def test_the_listing_counts_what_it_leaves_out():
    from rockfall_design.report.listed import SHOWN, listed_lines

    lines = listed_lines([_entry(cost=60_000.0 + i) for i in range(SHOWN + 3)])
    assert len(lines) == SHOWN + 1 and lines[-1].startswith("- ... and 3 more")
    assert listed_lines(None) == [] and listed_lines([]) == []


def test_design_yaml_and_the_report_name_the_undecided_designs():
    """The head of design.yaml and the report's "How sure" list the cheaper designs left
    undecided, each with the rocks that would decide it (issue 37, item 3)."""
    from types import SimpleNamespace

    import yaml

    from rockfall_design.optimiser.alternatives import SearchOutcome
    from rockfall_design.project import load_project
    from rockfall_design.report.documents import optimiser_sentences
    from rockfall_design.report.terminal import design_yaml
    project = load_project(Path(__file__).resolve().parents[1] / "data" / "design_small.yaml")
    concept = SimpleNamespace(name="spang", params=SimpleNamespace(
        model_dump=lambda mode: {"confidence": 0.95}))
    ev = SimpleNamespace(run=SimpleNamespace(project=project, seed=5,
                                             result=SimpleNamespace(n=9_206)),
                         concept=concept)
    best = SimpleNamespace(evaluation=ev, measures=[], name="fence", cost=75_000.0,
                           fresh_seed=1_000_008, fresh_rocks=18_412,
                           holds_on_fresh_rocks=True, fresh_looks=None, marginal=[])
    text = design_yaml(best, "p.yaml", 4_603, None, [_entry()])
    assert "# cheaper designs not admitted" in text
    assert "#   - Marginal, cheaper: fence 68,000: " in text
    assert "(--max-rocks 520000)" in text
    assert yaml.safe_load(text)["rocks"]["count"] == 9_206  # still a project check reads
    assert "not admitted" not in design_yaml(best, "p.yaml", 4_603, None, [])
    opt = SearchOutcome(alternatives=[], best=None, reason="", rocks=4_603, seed=5,
                        fresh_rocks=0, fresh_seed=6, wall_s=0.0, evaluations=0,
                        edit_runs=0, currency="EUR", marginal=[_entry()])
    lines = optimiser_sentences(opt)
    assert lines[-1].endswith("about 512,345 rocks would decide it (--max-rocks 520000)")
