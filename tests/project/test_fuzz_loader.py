"""Fuzzing the project loader with trees built from the schema (hardening, round 2).

Hypothesis builds YAML trees from the keys the schema knows (every section's
fields, read from the pydantic models, the plugin sections' keys read from
the built-in plugins' parameter models) with values of random type and size:
the right kind most of the time, anything else otherwise (strings, lists,
mappings, NaN, 1e300, 1e-300, huge integers), keys left out or unknown ones
added. Two properties:

- in-process, through the loader and the whole-file validation that every
  command runs (plugins included): a :class:`~rockfall_design.project.Project`
  or one :class:`~rockfall_design.errors.RockfallError` line, nothing else;
- through the command line, a batch in one child process guarded by a
  timeout: exit code 0, 1 or 2, and for 2 exactly one line, no traceback.
"""

from __future__ import annotations

import copy
import json
import math
import os
import subprocess
import sys
import typing
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel

from rockfall_design.api import validate_project
from rockfall_design.errors import RockfallError
from rockfall_design.plugins import load_registry
from rockfall_design.project import Project, ProjectError, load_project_text
from rockfall_design.project.messages import annotation_options

from .test_project import EXAMPLE_DATA

ROOT = Path(__file__).resolve().parents[2]
REGISTRY = load_registry()

# --------------------------------------------------------------------------------------
# values of every type, biased to the edges the limits are about
# --------------------------------------------------------------------------------------

numbers = st.one_of(
    st.integers(-5, 300),
    st.floats(-1e3, 1e3),
    st.sampled_from([0, -1, 0.5, 1e-300, 1e-9, 1e300, -1e300, 2**63, 10**30, math.nan,
                     math.inf, -math.inf, 1e9, 1e6, 10_000, 10_001]),
)
names = st.sampled_from(["talus", "rock", "fence", "ditch", "wall", "berm", "boulder_row",
                         "spang", "uniform", "normal", "lognormal", "rolling", "rn_rt",
                         "RX-100", "unit_prices", "p95", "max", "/dev/zero", ""])
scalars = st.one_of(numbers, names, st.text(max_size=6), st.booleans(), st.none())
junk = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4),
    st.dictionaries(st.one_of(names, st.text(max_size=4)), inner, max_size=3)),
    max_leaves=8)


def _section_models() -> dict[str, type[BaseModel]]:
    """Every pydantic model reachable from Project, by class name."""
    found: dict[str, type[BaseModel]] = {}

    def walk(model: type[BaseModel]) -> None:
        if model.__name__ in found:
            return
        found[model.__name__] = model
        for info in model.model_fields.values():
            stack = [info.annotation]
            while stack:
                ann = stack.pop()
                for option in annotation_options(ann):
                    if isinstance(option, type) and issubclass(option, BaseModel):
                        walk(option)
                    stack.extend(a for a in typing.get_args(option)
                                 if typing.get_origin(option) is not None)

    walk(Project)
    return found


MODELS = _section_models()
#: Keys of the plugin sections, from the built-in plugins' own models.
MEASURE_KEYS = sorted({k for cls in REGISTRY.measures.values() for k in cls.Params.model_fields})
SAFETY_KEYS = sorted({k for cls in REGISTRY.safety_concepts.values()
                      for k in cls.Params.model_fields})
SIZE_FIELDS = {"radius", "volume", "mass"}
ALL_KEYS = sorted({k for m in MODELS.values() for k in m.model_fields}
                  | set(MEASURE_KEYS) | set(SAFETY_KEYS))


def sizes() -> st.SearchStrategy:
    pair = st.lists(numbers, min_size=2, max_size=2)
    return st.one_of(numbers, st.dictionaries(
        st.sampled_from(["uniform", "normal", "lognormal", "weibull"]), pair,
        min_size=1, max_size=2))


def plugin_items(keys: list[str], selector: str, choices: list[str]) -> st.SearchStrategy:
    item = st.dictionaries(st.sampled_from(keys), st.one_of(numbers, names, junk), max_size=6)
    return st.builds(lambda d, kind: {selector: kind, **d}, item,
                     st.one_of(st.sampled_from(choices), scalars))


def value_for(annotation: Any, name: str, depth: int) -> st.SearchStrategy:
    """A value of roughly the annotation's kind, or (now and then) anything."""
    if name in SIZE_FIELDS:
        right = sizes()
    elif name == "measures":
        right = st.lists(plugin_items(["x", *MEASURE_KEYS], "type", sorted(REGISTRY.measures)),
                         max_size=3)
    elif name == "safety":
        right = plugin_items(SAFETY_KEYS, "concept", sorted(REGISTRY.safety_concepts))
    elif name == "candidates":
        right = st.lists(plugin_items(["x", "product", *MEASURE_KEYS], "type",
                                      sorted(REGISTRY.measures)), min_size=1, max_size=3)
    elif name == "residual":
        right = st.one_of(numbers, st.fixed_dictionaries({"fraction": numbers}))
    elif name == "products":
        right = st.one_of(names, st.dictionaries(names, junk, max_size=2))
    elif name in ("release", "x") and depth > 1:
        right = st.one_of(numbers, st.lists(numbers, min_size=2, max_size=2), junk)
    else:
        right = _by_type(annotation, depth)
    return st.one_of(right, right, right, junk)


def _by_type(annotation: Any, depth: int) -> st.SearchStrategy:
    options = annotation_options(annotation)
    for option in options:
        if isinstance(option, type) and issubclass(option, BaseModel):
            return model_tree(option, depth + 1) if depth < 4 else junk
    for option in options:
        origin = typing.get_origin(option)
        args = typing.get_args(option)
        if origin is list or origin is tuple:
            inner = _by_type(args[0], depth + 1) if args else numbers
            return st.lists(inner, max_size=5)
        if origin is dict:
            inner = _by_type(args[-1], depth + 1) if args else junk
            return st.dictionaries(names, inner, min_size=1, max_size=2)
        if origin is typing.Literal:
            return st.sampled_from(list(args))
        if option in (float, int):
            return numbers
        if option is bool:
            return st.booleans()
        if option is str:
            return names
    return junk


@st.composite
def model_tree(draw, model: type[BaseModel], depth: int = 0) -> dict[str, Any]:
    """A mapping with (most of) the model's keys, values by their fields, and a stray key."""
    tree: dict[str, Any] = {}
    for name, info in model.model_fields.items():
        if draw(st.integers(0, 9)) < (1 if info.is_required() else 5):
            continue  # left out
        tree[name] = draw(value_for(info.annotation, name, depth))
    if draw(st.integers(0, 9)) == 0:
        tree[draw(st.one_of(st.sampled_from(ALL_KEYS), st.text(max_size=5)))] = draw(junk)
    return tree


@st.composite
def projects(draw) -> Any:
    """A schema tree: whole, or one of the example's sections replaced by one."""
    if draw(st.booleans()):
        return draw(model_tree(Project))
    data = copy.deepcopy(EXAMPLE_DATA)
    for _ in range(draw(st.integers(1, 3))):
        name = draw(st.sampled_from(list(Project.model_fields)))
        data[name] = draw(value_for(Project.model_fields[name].annotation, name, 0))
    return data


def dump(data: Any) -> str:
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


# --------------------------------------------------------------------------------------
# in-process: the loader and the whole-file validation
# --------------------------------------------------------------------------------------


@settings(max_examples=int(os.environ.get("RF_EXAMPLES", "300")), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
@given(projects())
def test_schema_trees_load_or_fail_with_one_line(data):
    text = dump(data)
    # Catalogue paths are resolved against an empty directory of their own.
    try:
        project = load_project_text(text, "fuzz.yaml", base_dir="/nonexistent-dir")
        validate_project(project, REGISTRY)
    except RockfallError as err:
        message = str(err)
        assert "\n" not in message and message, message
        assert err.exit_code in (2, 3)
        if isinstance(err, ProjectError):  # located in the file (catalogues cannot be read)
            assert err.file == "fuzz.yaml" and message.startswith("fuzz.yaml"), message
        event(f"error {err.exit_code}")
        # A plugin fault here would be a built-in plugin failing on input that
        # should have been rejected as bad input.
        assert err.exit_code == 2, message
    else:
        event("valid")
        assert len(project.resolved_hash()) == 64


# --------------------------------------------------------------------------------------
# through the command line: a batch in one child process, guarded by a timeout
# --------------------------------------------------------------------------------------

DRIVER = """\
import contextlib, io, json, sys
from rockfall_design.cli.program import main

results = []
for path in sys.argv[1:]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(["simulate", path, "--rocks", "3", "--json"])
        except SystemExit as exc:
            code = exc.code
    results.append({"path": path, "code": code, "err": err.getvalue()})
print(json.dumps(results))
"""


@settings(max_examples=1, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                 HealthCheck.function_scoped_fixture])
@given(st.lists(projects(), min_size=int(os.environ.get("RF_CLI_EXAMPLES", "12")),
                max_size=int(os.environ.get("RF_CLI_EXAMPLES", "12"))))
def test_schema_trees_through_the_command_line(tmp_path, batch):
    paths = []
    for i, data in enumerate(batch):
        path = tmp_path / f"fuzz{i}.yaml"
        path.write_text(dump(data), encoding="utf-8")
        paths.append(str(path))
    # The timeout guards against a hang; it is not a measure of speed.
    proc = subprocess.run([sys.executable, "-c", DRIVER, *paths], capture_output=True,
                          text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    for result in json.loads(proc.stdout):
        code, err = result["code"], result["err"]
        assert code in (0, 1, 2), (result, Path(result["path"]).read_text())
        if code == 2:
            assert err.count("\n") == 1 and "Traceback" not in err, err
            assert err.startswith("rockfall-design: error: "), err


@pytest.mark.parametrize("text", [
    "name: x\nrocks: {count: 1e300}\n",
    "name: x\nengine: {max_chord_deg: 1e-300}\n",
    "name: x\ndesign: {max_measures: 1e300}\n",
])
def test_hand_picked_schema_trees(text):
    with pytest.raises(ProjectError):
        load_project_text(text, "fuzz.yaml")
