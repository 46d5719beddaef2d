"""The screening's tables of edited ground are told apart by a serial number, not by id()."""

from __future__ import annotations

import gc
from pathlib import Path

from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.judge.placing import build_concept, edited_section, place_measures
from rockfall_design.optimiser import Screening
from rockfall_design.optimiser.space import decode, variables_of
from rockfall_design.project import load_project

PROJECTS = Path(__file__).resolve().parents[2] / "projects"


def test_a_table_dropped_from_the_cache_does_not_lend_its_key_to_the_next(registry):
    # The search caches each option's outcomes per table. Keyed by id(table),
    # a table dropped from the cache of edited tables (it holds 256) freed its
    # id for the next one, whose rocks were then looked up under the old
    # table's outcomes.
    project = load_project(PROJECTS / "design_ditch_or_fence.yaml")
    spec = resolve_design(project, registry)
    concept = build_concept(project, registry)
    screen = Screening(project, registry, spec, concept, rocks=300, seed=3)
    (ci,) = sorted(screen.edit_candidates)
    variables = variables_of(spec.candidates, (ci,))
    serials = []
    for end in ("low", "high", "low"):
        vec = [getattr(v, end) for v in variables]
        measures = screen.measures(decode(spec.candidates, (ci,), variables, vec))
        placed = place_measures(project, registry, measures, screen.section)
        edited = edited_section(project, screen.section, placed)
        table = screen.table_for([p.footprint for p in placed], edited)
        serials.append(table.serial)
        assert screen.table_for([p.footprint for p in placed], edited) is table  # cached
        del table
        screen._edit_cache.clear()
        gc.collect()
    assert screen.bare.serial == 0
    # Three runs, the third of the first geometry again after the cache lost it.
    assert len(set(serials)) == 3 and 0 not in serials


def test_two_stands_on_one_stretch_are_two_tables(registry):
    # A protection forest keeps the ground: two stands on one stretch share
    # their points, and were one table when the cache knew edits by their
    # shape alone.
    project = load_project(PROJECTS / "design_forest_or_fence.yaml")
    spec = resolve_design(project, registry)
    concept = build_concept(project, registry)
    screen = Screening(project, registry, spec, concept, rocks=300, seed=3)
    (ci,) = sorted(screen.edit_candidates)
    variables = variables_of(spec.candidates, (ci,))
    tables = []
    for stems in ("low", "high"):
        vec = [getattr(v, "high" if v.name == "stems_per_ha" and stems == "high" else "low")
               for v in variables]
        measures = screen.measures(decode(spec.candidates, (ci,), variables, vec))
        placed = place_measures(project, registry, measures, screen.section)
        edited = edited_section(project, screen.section, placed)
        tables.append(screen.table_for([p.footprint for p in placed], edited))
    assert tables[0] is not tables[1] and tables[0].serial != tables[1].serial
