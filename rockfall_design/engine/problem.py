"""What the engine is given and what it returns, as plain records of arrays.

The section (ground and materials), the rocks' releases, the settings, the
barrier table (:func:`barrier_table`) and the result of a run
(:class:`EnsembleResult`); :func:`rockfall_design.engine.run_ensemble`
runs them."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from . import columns
from .profile import centre_path


@dataclass(frozen=True)
class Material:
    """Impact and contact parameters of one ground material.

    Attributes
    ----------
    impact_model : str
        ``"spang"`` (restitution e, friction mu, spin), ``"rn_rt"``
        (lumped-mass v_n' = -Rn v_n, v_t' = Rt v_t) or ``"rough_soft"``
        (spang's impact with a resistance from the block's radius against the
        ground's obstacles and from its softness, growing with the speed;
        PHYSICS.md, "The rough_soft law").
    restitution : float
        e (spang) or Rn (rn_rt), in [0, 1].
    friction : float
        Coulomb friction coefficient mu (-), >= 0.
    rolling_resistance : float
        Rolling-resistance coefficient mu_r (-), >= 0.
    tangential_restitution : float
        Rt (rn_rt only), in [0, 1].
    velocity_scaling : bool
        Pfeiffer & Bowen (1989) scaling of the normal restitution.
    velocity_scaling_k : float
        K of that scaling (m/s).
    roughness_deg : float
        Standard deviation of the tilt of the impact normal (degrees).
    roughness_height_m : float
        Roughness as a height h_r (m), PlatRock's convention: the normal tilts
        against the motion by an angle uniform in [0, atan(h_r / r)].
    sd_restitution, sd_friction, sd_rolling_resistance : float
        Standard deviations of the per-impact draws.
    obstacle_height_m : float
        Mean obstacle height h_o of the ground (m), rough_soft only.
    drag_speed_ms : float
        Speed V_s (m/s) at which the resistance has doubled, rough_soft only;
        0 for a resistance that does not grow with the speed.
    stems_per_ha : float
        A forest on this ground: stems per hectare of map area; 0 for none
        (``engine.forest``).
    dbh_mean_cm, dbh_sd_cm : float
        Mean and standard deviation of the stems' diameter at breast height (cm).
    tree_height_m : float
        Height above the ground (m) up to which a passing rock's centre meets
        a stem.
    """

    impact_model: str = "spang"
    restitution: float = 0.35
    friction: float = 0.5
    rolling_resistance: float = 0.0
    tangential_restitution: float = 1.0
    velocity_scaling: bool = False
    velocity_scaling_k: float = 9.144
    roughness_deg: float = 0.0
    sd_restitution: float = 0.0
    sd_friction: float = 0.0
    sd_rolling_resistance: float = 0.0
    roughness_height_m: float = 0.0
    obstacle_height_m: float = 0.0
    drag_speed_ms: float = 0.0
    stems_per_ha: float = 0.0
    dbh_mean_cm: float = 0.0
    dbh_sd_cm: float = 0.0
    tree_height_m: float = 0.0

    def row(self) -> np.ndarray:
        """This material as a row of the engine's material table."""
        out = np.zeros(columns.N_MAT_COLS)
        codes = {"spang": columns.MODEL_SPANG, "rn_rt": columns.MODEL_RN_RT,
                 "rough_soft": columns.MODEL_ROUGH_SOFT}
        out[columns.M_MODEL] = codes[self.impact_model]
        out[columns.M_E] = self.restitution
        out[columns.M_RT] = self.tangential_restitution
        out[columns.M_MU] = self.friction
        out[columns.M_MUR] = self.rolling_resistance
        # rough_soft's normal restitution always falls with the impact speed.
        vscale = self.velocity_scaling or self.impact_model == "rough_soft"
        out[columns.M_VSCALE] = 1.0 if vscale else 0.0
        out[columns.M_VSK] = self.velocity_scaling_k
        out[columns.M_ROUGH] = np.radians(self.roughness_deg)
        out[columns.M_SD_E] = self.sd_restitution
        out[columns.M_SD_MU] = self.sd_friction
        out[columns.M_SD_MUR] = self.sd_rolling_resistance
        out[columns.M_ROUGH_H] = self.roughness_height_m
        out[columns.M_OBST] = self.obstacle_height_m
        out[columns.M_VDRAG] = self.drag_speed_ms
        # The engine's forest in SI units: stems per m^2, diameters in m.
        out[columns.M_STEMS] = self.stems_per_ha / 1e4
        out[columns.M_DBH] = self.dbh_mean_cm / 100.0
        out[columns.M_SD_DBH] = self.dbh_sd_cm / 100.0
        out[columns.M_TREE_H] = self.tree_height_m
        return out


@dataclass(frozen=True)
class Section:
    """A slope section: ground polyline and the material of each segment.

    Attributes
    ----------
    x, y : ndarray of float
        Ground vertices (m), x strictly increasing, at least two.
    segment_material : ndarray of int
        Index into ``materials`` for each of the ``len(x) - 1`` segments.
    materials : tuple of Material
    """

    x: np.ndarray
    y: np.ndarray
    segment_material: np.ndarray
    materials: tuple[Material, ...]

    def __post_init__(self) -> None:
        x = np.ascontiguousarray(self.x, dtype=float)
        y = np.ascontiguousarray(self.y, dtype=float)
        sm = np.ascontiguousarray(self.segment_material, dtype=np.int64)
        if x.ndim != 1 or x.shape != y.shape or x.size < 2:
            raise ValueError("a section needs at least two (x, y) vertices")
        if not np.all(np.diff(x) > 0):
            raise ValueError("section x must be strictly increasing")
        if sm.shape != (x.size - 1,):
            raise ValueError("one material index per segment is needed")
        if sm.min() < 0 or sm.max() >= len(self.materials):
            raise ValueError("material index out of range")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "segment_material", sm)

    @property
    def forested(self) -> bool:
        """Whether a material of the section carries a forest (``Material.stems_per_ha``)."""
        return any(m.stems_per_ha > 0.0 for m in self.materials)

    def material_table(self) -> np.ndarray:
        return np.vstack([m.row() for m in self.materials])

    def ground_height(self, x: np.ndarray | float) -> np.ndarray:
        """Ground height (m) at ``x``, linear between vertices."""
        return np.interp(x, self.x, self.y)

    def centre_path(self, radius: float, max_chord_deg: float = 5.0):
        """Centre path (px, py, pseg) of a sphere of ``radius`` (m)."""
        return centre_path(
            self.x, self.y, np.arange(self.x.size - 1), float(radius), np.radians(max_chord_deg)
        )


@dataclass(frozen=True)
class Releases:
    """Per-rock initial conditions (all arrays of one length N).

    Attributes
    ----------
    radius : ndarray
        Rock radius (m).
    density : float or ndarray
        Rock density (kg/m^3).
    x : ndarray
        Release x of the rock centre (m).
    height : ndarray
        Clearance above the ground at release (m), >= 0.
    vx, vy : ndarray
        Initial velocity (m/s).
    spin : ndarray
        Initial angular velocity (rad/s), counter-clockwise positive.
    spin_rolling : ndarray of bool
        Start with the spin of rolling along the ground instead of ``spin``.
    zone : ndarray of int
        Index of the release zone each rock came from (for reports).
    """

    radius: np.ndarray
    density: float | np.ndarray
    x: np.ndarray
    height: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    spin: np.ndarray
    spin_rolling: np.ndarray
    zone: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    def __len__(self) -> int:
        return int(np.asarray(self.radius).size)

    def joined(self, more: Releases) -> Releases:
        """These rocks followed by ``more`` (see :meth:`EnsembleResult.joined`)."""
        out = {}
        for f in fields(self):
            a, b = getattr(self, f.name), getattr(more, f.name)
            if f.name == "density" and np.ndim(a) == 0 and np.ndim(b) == 0 and a == b:
                out[f.name] = a
                continue
            if f.name == "density":
                a = np.broadcast_to(a, (len(self),))
                b = np.broadcast_to(b, (len(more),))
            out[f.name] = np.concatenate([np.asarray(a), np.asarray(b)])
        return Releases(**out)

    @property
    def mass(self) -> np.ndarray:
        return rock_mass(np.asarray(self.radius), self.density)


def rock_mass(radius: np.ndarray | float, density: np.ndarray | float) -> np.ndarray:
    """Mass (kg) of a solid sphere: m = 4/3 pi r^3 rho."""
    return 4.0 / 3.0 * np.pi * np.asarray(radius) ** 3 * np.asarray(density)


@dataclass(frozen=True)
class EngineSettings:
    """Numerical parameters of the engine (PHYSICS.md).

    Attributes
    ----------
    v_contact : float
        Outgoing normal speed (m/s) below which a rock stays in contact: a
        numerical floor (PHYSICS.md, "The transition to contact").
    contact_hop_ratio : float
        kappa (-): a rebound whose hop above the piece is lower than
        h_c = max(roughness_height_m, kappa r) continues in contact; 0 leaves
        the decision to ``v_contact`` alone. ILLUSTRATIVE default.
    v_stop : float
        Speed (m/s) below which a rock that the ground can hold is stopped.
    max_events : int
        Event limit per rock; a rock reaching it is reported as unresolved.
    max_chord_deg : float
        Largest turn (degrees) of an edge of the polygon replacing the arc of
        the centre path at a convex vertex.
    """

    v_contact: float = 0.05
    v_stop: float = 0.05
    max_events: int = 10_000
    max_chord_deg: float = 5.0
    contact_hop_ratio: float = columns.CONTACT_HOP_RATIO

    def vector(self) -> np.ndarray:
        out = np.zeros(columns.N_SETTINGS)
        out[columns.S_V_CONTACT] = self.v_contact
        out[columns.S_V_STOP] = self.v_stop
        out[columns.S_HOP_RATIO] = self.contact_hop_ratio
        out[columns.S_MAX_EVENTS] = self.max_events
        return out


@dataclass
class EnsembleResult:
    """Per-rock outcomes of an ensemble run.

    Attributes
    ----------
    radius, mass : ndarray, shape (N,)
        Rock radius (m) and mass (kg).
    status : ndarray of int8, shape (N,)
        How each path ended, index into ``STATUS_NAMES``.
    x_end, y_end : ndarray, shape (N,)
        Final position of the rock centre (m).
    max_x : ndarray, shape (N,)
        Largest x reached (m).
    n_impacts, n_events : ndarray of int, shape (N,)
    duration : ndarray, shape (N,)
        Duration of each path (s).
    stations : ndarray, shape (U,)
        The user's analysis stations (m).
    crossings : ndarray, shape (N, U, 5)
        First downslope passage of each station: passing height (m),
        vx, vy (m/s), w (rad/s), time (s); NaN where not crossed.
    grid : ndarray, shape (S,)
        Envelope stations (m), sorted, including the user stations.
    grid_height : ndarray of float32, shape (N, S)
        Passing height (m) at the first downslope passage, NaN if none.
    grid_energy : ndarray of float32, shape (N, S)
        Total kinetic energy (J) there.
    trajectories : list of ndarray
        Event states (columns x, y, vx, vy, w, t, mode) of the first rocks.
    barrier_outcome : ndarray of int8, shape (N, B)
        Outcome of each rock's first meeting with each barrier (``columns.O_*``),
        barriers in the order given.
    barrier_meeting : ndarray, shape (N, B, 4)
        Passing height (m), speed (m/s), total kinetic energy (J) and time (s)
        of that meeting; NaN if not met.
    caught_by : ndarray of int, shape (N,)
        Barrier that caught each rock (order given), or -1.
    grid_speed : ndarray of float32, shape (N, S), or (N, 0)
        Speed (m/s) at the first downslope passage of each envelope station
        (only with ``record_speed``).
    restart_x : ndarray, shape (R,)
        Restart stations (m), sorted.
    restart_state : ndarray, shape (N, R, columns.N_RESTART_COLS)
        Each rock's state at the first downslope passage of each restart
        station; NaN where it never passed.
    restart_rng : ndarray of uint64, shape (N, R)
        Each rock's random stream there.
    stems_met : ndarray of int32, shape (N,)
        Stems of a forest each rock met (``engine.forest``); 0 without forest.
        A resumed rock counts those it met after its restart station.
    stopped_by_forest : ndarray of bool, shape (N,)
        The rocks a stem stopped (their status is ``stopped``, at the stem).
    """

    radius: np.ndarray
    mass: np.ndarray
    status: np.ndarray
    x_end: np.ndarray
    y_end: np.ndarray
    max_x: np.ndarray
    n_impacts: np.ndarray
    n_events: np.ndarray
    duration: np.ndarray
    stations: np.ndarray
    crossings: np.ndarray
    grid: np.ndarray
    grid_height: np.ndarray
    grid_energy: np.ndarray
    trajectories: list[np.ndarray]
    barrier_outcome: np.ndarray
    barrier_meeting: np.ndarray
    caught_by: np.ndarray
    grid_speed: np.ndarray
    restart_x: np.ndarray
    restart_state: np.ndarray
    restart_rng: np.ndarray
    stems_met: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    stopped_by_forest: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    @property
    def n(self) -> int:
        return int(self.status.size)

    @property
    def events_total(self) -> int:
        return int(self.n_events.sum())

    #: Fields that are not one row per rock (the stations, the envelope grid,
    #: the restart stations and the kept trajectories of the first rocks).
    _SHARED = ("stations", "grid", "trajectories", "restart_x")

    def joined(self, more: EnsembleResult) -> EnsembleResult:
        """This run followed by ``more``: the rocks of both, in order.

        ``more`` must be the next rocks of the same run (same section,
        barriers, stations, settings and key, its ``first_index`` this run's
        ``n``): every rock draws from its own stream, so the result is the
        one a run of all the rocks at once gives, bit for bit. The kept
        trajectories are this run's.

        The per-rock fields are joined when first read, each once: the
        optimiser's sequential looks go on from one another and read the
        barrier records, never the envelope grid (``grid_height`` and
        ``grid_energy``, 1.6 kB a rock at 201 envelope points), so a chain
        of joins holds the runs' rows as they came, copies a field when it
        is read and copies the grid at most once, for the report of the
        chosen design.
        """
        for f in ("stations", "grid", "restart_x"):
            if not np.array_equal(getattr(self, f), getattr(more, f)):
                raise ValueError(f"joined runs differ in {f}")
        out = object.__new__(EnsembleResult)
        out.stations, out.grid = self.stations, self.grid
        out.trajectories, out.restart_x = self.trajectories, self.restart_x
        out.__dict__[_PENDING] = {f.name: self._parts(f.name) + more._parts(f.name)
                                  for f in fields(self) if f.name not in self._SHARED}
        return out

    def _parts(self, name: str) -> list[np.ndarray]:
        """The rows of per-rock field ``name``, as the runs joined into this one gave them."""
        parts = self.__dict__.get(_PENDING, {}).get(name)
        return [getattr(self, name)] if parts is None else list(parts)

    def __getattr__(self, name: str) -> np.ndarray:
        """A per-rock field of a joined result, read for the first time: join its rows now.

        Python calls this only for a name that the instance does not hold:
        set here, the joined field is an ordinary attribute from then on.
        """
        pending = self.__dict__.get(_PENDING)
        parts = None if pending is None else pending.get(name)
        if parts is None:
            # Another thread may have just joined it (it is set before it is dropped).
            if name in self.__dict__:
                return self.__dict__[name]
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        value = np.concatenate(parts)
        self.__dict__[name] = value
        # A new dict, not a pop: a copy of this result (copy.copy) shares the old one.
        self.__dict__[_PENDING] = {k: v for k, v in pending.items() if k != name}
        return value


#: Where a joined :class:`EnsembleResult` keeps the rows of its per-rock
#: fields not yet read (field name -> the runs' arrays, in rock order).
_PENDING = "_pending_rows"


def barrier_table(
    x: float,
    height_m: float,
    capacity_j: float,
    behaviour: int,
    restitution: float = 0.0,
    gap_m: float = 0.0,
    spacing_m: float = 1.0,
    sel_j: float = 0.0,
    elongation_sel_m: float = 0.0,
    elongation_mel_m: float = 0.0,
) -> np.ndarray:
    """One row of the engine's barrier table (see ``columns.BR_*``).

    Parameters
    ----------
    x : float
        Station (m).
    height_m : float
        Height of the top above ground (m).
    capacity_j : float
        Energy capacity (J); ``np.inf`` for none.
    behaviour : int
        ``columns.B_NET``, ``columns.B_RIGID`` or ``columns.B_BLOCKS``.
    restitution : float
        Rebound restitution of a rigid barrier (-).
    gap_m, spacing_m : float
        Clear gap and spacing of a boulder row (m).
    sel_j, elongation_sel_m, elongation_mel_m : float
        A net's service energy level (J) and its elongations in the SEL and
        MEL tests (m): a rock it catches comes to rest its braking distance
        downslope (:func:`~rockfall_design.engine.barriers.braking_distance`);
        0 for figures not given (no elongation at MEL: no braking distance).
    """
    row = np.zeros(columns.N_BARRIER_COLS)
    row[columns.BR_X] = x
    row[columns.BR_H] = height_m
    row[columns.BR_CAP] = capacity_j
    row[columns.BR_BEH] = behaviour
    row[columns.BR_E] = restitution
    row[columns.BR_GAP] = gap_m
    row[columns.BR_SPACING] = spacing_m
    row[columns.BR_SEL] = sel_j
    row[columns.BR_D_SEL] = elongation_sel_m
    row[columns.BR_D_MEL] = elongation_mel_m
    return row
