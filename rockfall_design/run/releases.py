"""The engine's inputs from a project: the section, the settings and the rocks.

Random numbers: one ``np.random.SeedSequence(seed)`` is split into
independent child sequences, one per quantity (engine streams, zone, x
within the zone, rock size). Each quantity is drawn for all rocks at once
from its own generator, so the first N rocks of a larger run are exactly the
rocks of a run of N: a run can be cut short or extended and stay comparable.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

import numpy as np

from ..engine import EngineSettings, Material, Releases, Section
from ..project.schema import MAX_RADIUS_M, MIN_RADIUS_M, Forest

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project

__all__ = [
    "ReleaseStream",
    "draw_releases",
    "engine_key",
    "engine_settings",
    "section_from_project",
    "size_classes",
]

# Child sequences of the run's SeedSequence, by purpose. Never reorder: that
# would change every result for a given seed.
_SEED_ENGINE, _SEED_ZONE, _SEED_X, _SEED_SIZE = range(4)
_N_SEED_CHILDREN = 4


def section_from_project(project: Project) -> Section:
    """The engine's slope section (ground polyline and materials) of a project."""
    names = list(project.materials)
    mats = []
    for name in names:
        m = project.materials[name]
        mats.append(
            Material(
                impact_model=m.impact_model,
                restitution=m.restitution,
                friction=m.friction,
                rolling_resistance=m.rolling_resistance,
                tangential_restitution=(
                    m.tangential_restitution if m.tangential_restitution is not None else 1.0
                ),
                velocity_scaling=m.velocity_scaling,
                velocity_scaling_k=m.velocity_scaling_k,
                roughness_deg=m.roughness_deg,
                roughness_height_m=m.roughness_height_m,
                obstacle_height_m=m.obstacle_height_m,
                drag_speed_ms=m.drag_speed_ms or 0.0,
                sd_restitution=m.scatter.restitution,
                sd_friction=m.scatter.friction,
                sd_rolling_resistance=m.scatter.rolling_resistance,
                **_forest_fields(m.forest),
            )
        )
    pts = np.asarray(project.slope.points, dtype=float)
    seg_mat = np.array([names.index(n) for n in project.slope.materials], dtype=np.int64)
    return Section(pts[:, 0], pts[:, 1], seg_mat, tuple(mats))


def _forest_fields(forest: Forest | None) -> dict[str, float]:
    """The engine material's forest fields of a material's ``forest:`` (none: no forest)."""
    if forest is None:
        return {}
    return {"stems_per_ha": forest.stems_per_ha, "dbh_mean_cm": forest.dbh_mean_cm,
            "dbh_sd_cm": forest.dbh_sd_cm, "tree_height_m": forest.tree_height_m}


def engine_settings(project: Project) -> EngineSettings:
    e = project.engine
    return EngineSettings(
        v_contact=e.v_contact,
        v_stop=e.v_stop,
        max_events=e.max_events,
        max_chord_deg=e.max_chord_deg,
        contact_hop_ratio=e.contact_hop_ratio,
    )


def _children(seed: int) -> list[np.random.SeedSequence]:
    return np.random.SeedSequence(int(seed)).spawn(_N_SEED_CHILDREN)


def engine_key(seed: int) -> int:
    """The 64-bit key of the engine's per-rock random streams for ``seed``."""
    return int(_children(seed)[_SEED_ENGINE].generate_state(1, np.uint64)[0])


def _draw_size(
    kind: str,
    a: float,
    b: float,
    n: int,
    rng: np.random.Generator,
    upper: float = np.inf,
    lower: float = 0.0,
) -> np.ndarray:
    """Draw n values of a size quantity (radius m, volume m^3 or mass kg).

    Normal and lognormal sizes are drawn by inverting their CDF, truncated to
    (0, ``upper``]: one uniform per rock keeps the draws of the first rocks
    independent of n. Where the cut-off lies beyond float precision of the
    CDF (every realistic case) the draws are those of the whole distribution.
    Draws below ``lower`` are raised to it: a clip rather than a truncation,
    so that every draw above it stays bit for bit what it was.
    """
    return np.maximum(_draw_size_unclipped(kind, a, b, n, rng, upper), lower)


def _draw_size_unclipped(
    kind: str, a: float, b: float, n: int, rng: np.random.Generator, upper: float
) -> np.ndarray:
    if kind == "fixed":
        return np.full(n, float(a))
    u = rng.random(n)
    if kind == "uniform":
        return a + (b - a) * u
    # The standard normal CDF and its inverse (what scipy.stats.norm.cdf/ppf
    # evaluate), from scipy.special, which imports in a fraction of the time.
    from scipy.special import ndtr, ndtri

    if kind == "normal":
        if b <= 0.0:
            return np.full(n, float(a))
        lo, hi = ndtr(-a / b), ndtr((upper - a) / b)
        return np.minimum(a + b * ndtri(lo + (hi - lo) * u), upper)
    if kind == "lognormal":
        if b <= 0.0:
            return np.full(n, float(a))
        hi = ndtr(np.log(upper / a) / b)
        return np.minimum(a * np.exp(b * ndtri(hi * u)), upper)
    raise ValueError(f"unknown size distribution {kind!r}")


def size_classes(radius: np.ndarray, step: float) -> np.ndarray:
    """Each radius rounded to the nearest of a geometric grid of radii (size classes).

    Parameters
    ----------
    radius : ndarray of float
        Drawn radii (m), > 0.
    step : float
        Relative step of the grid (-): its radii are ``(1 + step) ** k`` m for
        whole k. 0 returns the radii as they are.

    Returns
    -------
    ndarray of float
        The class radius of each rock (m), clipped to the radius limits of a
        project (``MIN_RADIUS_M``, ``MAX_RADIUS_M``).

    Notes
    -----
    The rounding is to the nearest grid radius in log scale, so a class
    radius ``rc`` of a drawn radius ``r`` has ``|ln(rc / r)| <= ln(1 + step) / 2``:
    it moves by at most ``sqrt(1 + step) - 1 < step / 2`` relative (0.2497 %
    at the default 0.5 %), a mass by at most ``(1 + step) ** 1.5 - 1`` (0.751 %).
    Every class radius is one number computed from its k alone, so all rocks
    of a class have the same radius to the bit and share one centre path on
    a survey (``engine.run_ensemble``), which is what the classes are for
    (so dense surveys run fast). The grid is anchored at 1 m, whatever the run's
    sizes, so a chunk of a run and the whole run round alike.
    """
    r = np.asarray(radius, dtype=float)
    if step <= 0.0:
        return r.copy()
    log_step = np.log1p(step)
    k = np.rint(np.log(r) / log_step)
    return np.clip(np.exp(k * log_step), MIN_RADIUS_M, MAX_RADIUS_M)


class ReleaseStream:
    """Draws the size and release conditions of a run's rocks, a chunk at a time.

    Each quantity has its own generator, consumed in rock order, so drawing
    the rocks in chunks gives exactly the rocks drawn all at once.

    Parameters
    ----------
    project : Project
    seed : int
        Seed of the run.
    """

    def __init__(self, project: Project, seed: int) -> None:
        ch = _children(seed)
        self._rocks = project.rocks
        zones = self._rocks.release
        w = np.array([z.weight for z in zones], dtype=float)
        self._p = w / w.sum()
        self._zone_rng = np.random.default_rng(ch[_SEED_ZONE])
        self._x_rng = np.random.default_rng(ch[_SEED_X])
        self._size_rng = np.random.default_rng(ch[_SEED_SIZE])
        #: Relative step of the size classes radii are rounded to (0: none).
        self.size_step = project.size_step
        self.drawn = 0

    def fork(self) -> ReleaseStream:
        """A copy of this stream where it stands: it draws the rocks this one would draw
        next, and drawing from it leaves this one where it is."""
        out = copy.copy(self)
        out._zone_rng = copy.deepcopy(self._zone_rng)
        out._x_rng = copy.deepcopy(self._x_rng)
        out._size_rng = copy.deepcopy(self._size_rng)
        return out

    def draw(self, n: int) -> Releases:
        """The next ``n`` rocks.

        Returns
        -------
        Releases
            Radius (m), density (kg/m^3), release x (m), clearance (m),
            velocity (m/s), spin (rad/s) and zone index of each rock. On a
            survey the radii are those of the rocks' size classes
            (:func:`size_classes`, step :attr:`size_step`).
        """
        rocks = self._rocks
        zones = rocks.release
        if len(zones) == 1:
            zone = np.zeros(n, dtype=np.int64)
        else:
            zone = self._zone_rng.choice(len(zones), size=n, p=self._p)
        lo = np.array([z.x[0] for z in zones])[zone]
        hi = np.array([z.x[1] for z in zones])[zone]
        u = self._x_rng.random(n)
        x = lo + (hi - lo) * u
        spec = rocks.size
        q = _draw_size(spec.kind, spec.a, spec.b, n, self._size_rng, rocks.max_size,
                       rocks.min_size)
        rho = float(rocks.density)
        if rocks.size_quantity == "radius":
            radius = q
        else:
            volume = q if rocks.size_quantity == "volume" else q / rho
            radius = np.cbrt(3.0 * volume / (4.0 * np.pi))
        if self.size_step > 0.0:
            # On a survey, rocks of one size class share one centre path (size_classes).
            radius = size_classes(radius, self.size_step)
        height = np.array([z.height for z in zones], dtype=float)[zone]
        vel = np.array([z.velocity for z in zones], dtype=float).reshape(-1, 2)[zone]
        rolling = np.array([z.spin == "rolling" for z in zones])[zone]
        spin = np.array([0.0 if z.spin == "rolling" else float(z.spin) for z in zones])[zone]
        self.drawn += n
        return Releases(
            radius=radius,
            density=rho,
            x=x,
            height=height,
            vx=vel[:, 0].copy(),
            vy=vel[:, 1].copy(),
            spin=spin,
            spin_rolling=rolling,
            zone=zone,
        )


def draw_releases(project: Project, n: int, seed: int) -> Releases:
    """Draw the size and release conditions of ``n`` rocks from ``seed``.

    Parameters
    ----------
    project : Project
    n : int
        Number of rocks.
    seed : int
        Seed of the run.

    Returns
    -------
    Releases
        See :meth:`ReleaseStream.draw`.
    """
    return ReleaseStream(project, seed).draw(n)
