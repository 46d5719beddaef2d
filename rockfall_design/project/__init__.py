"""The project file: ``project.yaml`` -> a validated, normalised :class:`Project`.

Loading is strict and reports the first problem as one line,
``file:line: key.path: message`` (a :class:`~rockfall_design.errors.ProjectError`):

- every section forbids unknown keys, with "did you mean" for near misses;
- numbers must be finite YAML numbers: booleans, strings such as ``"0.5"``,
  ``.nan`` and ``.inf`` are rejected;
- duplicate keys in a mapping are an error (plain YAML keeps the last one);
- cross-field rules (materials used by the slope are defined, release zones,
  stations and the protection lie on the section, ...) name the key involved.

The plugin sections ``measures:`` (a list of mappings, each with a string
``type``) and ``safety:`` (a mapping with a string ``concept``, default
``spang``) are kept raw, as plain data with finite numbers: the plugins that
own them are loaded later, and their parameters are validated then with
:meth:`Project.validate_params`, which locates problems in the file as the
core sections do (:meth:`Project.error_at`, :meth:`Project.unknown_name`).

Normalisation (what the models hold, whatever short form the file used):

- ``slope.materials`` is always a list with one material name per segment;
- ``rocks.release`` is always a list of :class:`ReleaseZone`;
- ``ReleaseZone.x`` is always a ``(min, max)`` tuple in m;
- ``rocks.radius`` / ``rocks.volume`` / ``rocks.mass`` hold a :class:`SizeSpec`
  (exactly one of them is set); :attr:`Rocks.size` and
  :attr:`Rocks.size_quantity` give the one that is set.

:meth:`Project.resolved_dict` writes the normalised project back in the
file's own syntax with every default filled in, so it is itself a valid
project file; :meth:`Project.resolved_hash` is the sha256 of its canonical JSON.

Units are SI throughout: m, m/s, rad/s, kg, m3, kg/m3; angles in degrees
where the key says ``_deg``.

The package, one room each (the names above are all importable from here):

- :mod:`.messages`: values described, "did you mean", key paths and lines,
  pydantic errors (of the core sections and of plugin parameters) as one line;
- :mod:`.fields`: the strict scalar types, the base model, the plugin
  sections kept raw;
- :mod:`.schema`: the core sections (slope, materials, rocks, release,
  analysis, protect, engine) and the limits;
- :mod:`.locator`: :class:`Locator` and :func:`params_problem`, plugin
  parameters validated with their problems located in the file;
- :mod:`.design`: the ``design:`` section (:class:`Design`, :class:`DesignCosts`,
  candidates, residual, site, catalogues);
- :mod:`.study`: the ``study:`` section (:class:`StudySpec`: inputs varied
  by their path, grid or Latin hypercube scenarios);
- :mod:`.calibrate`: the ``calibrate:`` section (:class:`CalibrateSpec`:
  observed stops, inputs fitted by their path with their ranges, levels);
- :mod:`.model`: :class:`Project`, the whole file;
- :mod:`.loading`: YAML with line numbers and limits, :func:`load_project`,
  :func:`load_project_text`, :func:`dump_yaml`, and :func:`load_corridor`
  for a file that may list ``sections:``;
- :mod:`.corridor`: :class:`Corridor`, a file of several sections, each an
  ordinary :class:`Project` (shared keys merged in, its own seed).
"""

# The package's face: every name callers import from ``rockfall_design.project``.
# The public ones are listed in __all__; the others (limits and field types) are
# re-exported by name.
from ..errors import ProjectError as ProjectError
from .calibrate import CalibrateSpec
from .corridor import Corridor, CorridorSection, section_seed
from .design import Design, DesignCosts, ResidualFraction, Site
from .fields import Boolean as Boolean
from .fields import Fraction as Fraction
from .fields import Integer as Integer
from .fields import NonNegative as NonNegative
from .fields import Number as Number
from .fields import Positive as Positive
from .fields import String as String
from .loading import load_corridor, load_corridor_text, load_project, load_project_text
from .locator import Locator, params_problem
from .messages import describe as describe
from .messages import did_you_mean as did_you_mean
from .messages import to_project_error as to_project_error
from .model import Project
from .schema import MAX_COORDINATE_M as MAX_COORDINATE_M
from .schema import MAX_DENSITY as MAX_DENSITY
from .schema import MAX_DESIGN_MEASURES as MAX_DESIGN_MEASURES
from .schema import MAX_ENVELOPE_POINTS as MAX_ENVELOPE_POINTS
from .schema import MAX_FAMILIES as MAX_FAMILIES
from .schema import MAX_PERCENTILES as MAX_PERCENTILES
from .schema import MAX_RADIUS_M as MAX_RADIUS_M
from .schema import MAX_RELEASE_HEIGHT_M as MAX_RELEASE_HEIGHT_M
from .schema import MAX_RELEASE_SPEED as MAX_RELEASE_SPEED
from .schema import MAX_RELEASE_SPIN as MAX_RELEASE_SPIN
from .schema import MAX_ROCKS as MAX_ROCKS
from .schema import MAX_STATIONS as MAX_STATIONS
from .schema import MIN_CHORD_DEG as MIN_CHORD_DEG
from .schema import MIN_DENSITY as MIN_DENSITY
from .schema import MIN_RADIUS_M as MIN_RADIUS_M
from .schema import (
    Analysis,
    EngineConfig,
    Material,
    Protect,
    ReleaseZone,
    Rocks,
    Scatter,
    SizeSpec,
    Slope,
)
from .schema import SizeField as SizeField
from .study import Range, Sample, StudySpec
from .yaml_file import dump_yaml

__all__ = [
    "Corridor",
    "CorridorSection",
    "load_corridor",
    "load_corridor_text",
    "section_seed",
    "dump_yaml",
    "Analysis",
    "Design",
    "DesignCosts",
    "Locator",
    "ResidualFraction",
    "Site",
    "params_problem",
    "EngineConfig",
    "Material",
    "Project",
    "Protect",
    "ReleaseZone",
    "Rocks",
    "Scatter",
    "SizeSpec",
    "Slope",
    "Range",
    "Sample",
    "StudySpec",
    "CalibrateSpec",
    "load_project",
    "load_project_text",
]
