"""A forest: the stems a rock meets on forested ground and the energy they take.

The stand is a Poisson field of stems in map area, of density N (stems/m^2)
and stem diameters D drawn from a normal distribution truncated to
[0, 2 E[D]] (symmetric, so its mean stays E[D]). In the 2-D section a rock of
radius r meets every stem whose axis lies within D / 2 + r of its line of
travel: it sweeps a strip of width D + 2r. Over a horizontal distance dx the
number of stems met is Poisson with mean N (E[D] + 2r) dx, so the distance to
the next stem along x is exponential with rate

    lambda = N (E[D] + 2 r)        (1/m),

and the diameter of the stem met is the size-biased one, of density
proportional to f(D) (D + 2r) (a thick stem is met more often than a thin
one). The same law underlies Rockyfor3D's tree impacts (Dorren 2016) and
Rockfor.NET (Berger & Dorren 2007). Stems stand in map area, so the rate
is per metre of horizontal travel (x), not of slope length.

A stem is met only if the rock's centre passes below the stem height
``M_TREE_H`` above the ground there (a rock flying over the canopy passes).
The energy a stem can take is Dorren & Berger's (2006) fit to full-scale
impacts on stems,

    E_max = 38.7 D^2.31     (J, D in cm).

A rock whose kinetic energy (translation and spin) is at most E_max stops at
the stem; else it loses E_max and goes on in the same direction, velocity and
spin scaled by sqrt((E - E_max) / E).

Limits: every impact is taken as central (the stem takes its full E_max; an
eccentric impact takes less and deflects the rock, which a 2-D section cannot
show), so a stand takes at most the energy the fit gives; stems are met only
on downslope travel; a stem once passed is not met again.

References
----------
.. [1] Dorren, L.K.A. and Berger, F. (2006). Stem breakage of trees and
   energy dissipation during rockfall impacts. Tree Physiology 26, 63-71.
.. [2] Dorren, L.K.A. (2016). Rockyfor3D (v5.2) revealed - Transparent
   description of the complete 3D rockfall model. ecorisQ paper.
.. [3] Berger, F. and Dorren, L.K.A. (2007). Principles of the tool
   Rockfor.NET for quantifying the rockfall hazard below a protection
   forest. Schweizerische Zeitschrift fur Forstwesen 158, 157-165.
"""

from __future__ import annotations

import numpy as np

from .columns import M_DBH, M_SD_DBH, M_STEMS, M_TREE_H
from .flight import locate, path_height
from .jit import hot
from .records import WORK_CTX, WORK_STEM
from .rng import next_uniform_in

#: Slots of a rock's restart context (``RockOut.work[WORK_CTX:]``) that hold
#: the forest's state: x of the next stem (m, inf for none), its material
#: row, the stems met, 1 if a stem stopped the rock.
F_X = WORK_STEM - WORK_CTX
F_MAT = F_X + 1
F_N = F_X + 2
F_STOP = F_X + 3

#: The slot of the rock's random state that the forest draws from (``rng.forest_stream``).
STREAM = 1

#: Dorren & Berger (2006): E_max = STEM_E_COEF * (D in cm) ** STEM_E_EXP (J).
STEM_E_COEF = 38.7
STEM_E_EXP = 2.31


@hot
def stem_energy(dbh: float) -> float:
    """Energy (J) a stem of diameter ``dbh`` (m) takes at most (Dorren & Berger 2006)."""
    return STEM_E_COEF * (100.0 * dbh) ** STEM_E_EXP


@hot
def has_forest(mats) -> bool:
    """Whether any material of the table carries a forest."""
    for i in range(mats.shape[0]):
        if mats[i, M_STEMS] > 0.0:
            return True
    return False


@hot
def next_stem(px, pseg, seg_mat, mats, r, x, ctx, rng):
    """Place the next stem a rock at ``x`` moving downslope meets; into ``ctx``.

    Walks the pieces of the centre path ``px`` (m) from ``x``, spending an
    exponential draw E ~ Exp(1) against the integrated rate
    N (E[D] + 2r) dx of each forested piece (``M_STEMS`` of its material).
    No draw is made when no forested piece lies ahead (``ctx[F_X]`` = inf),
    so a section without forest uses no random numbers for it.
    """
    n = px.shape[0] - 1
    k = int(np.searchsorted(px, x, side="right")) - 1
    k = min(max(k, 0), n - 1)
    first = -1
    for j in range(k, n):
        if mats[seg_mat[pseg[j]], M_STEMS] > 0.0 and px[j + 1] > x:
            first = j
            break
    ctx[F_X] = np.inf
    if first < 0:
        return
    e = -np.log(1.0 - next_uniform_in(rng, STREAM))
    for j in range(first, n):
        mat = seg_mat[pseg[j]]
        dens = mats[mat, M_STEMS]
        a = max(px[j], x)
        length = px[j + 1] - a
        if dens <= 0.0 or length <= 0.0:
            continue
        lam = dens * (mats[mat, M_DBH] + 2.0 * r)
        if lam * length >= e:
            ctx[F_X] = a + e / lam
            ctx[F_MAT] = mat
            return
        e -= lam * length


@hot
def draw_dbh(mats, mat, r, rng):
    """The diameter (m) of the stem a rock of radius ``r`` meets (size-biased).

    Rejection from the stand's truncated normal, accepting D with probability
    (D + 2r) / (D_max + 2r), D_max = 2 E[D]: the accepted D has density
    proportional to f(D) (D + 2r).
    """
    mean = mats[mat, M_DBH]
    sd = mats[mat, M_SD_DBH]
    if sd <= 0.0:
        return mean
    top = 2.0 * mean + 2.0 * r
    for _ in range(256):
        # Box-Muller on the forest's stream; rejection to [0, 2 mean] and by size.
        u1 = 1.0 - next_uniform_in(rng, STREAM)
        u2 = next_uniform_in(rng, STREAM)
        d = mean + sd * np.sqrt(-2.0 * np.log(u1)) * np.cos(2.0 * np.pi * u2)
        if 0.0 <= d <= 2.0 * mean and next_uniform_in(rng, STREAM) * top <= d + 2.0 * r:
            return d
    # Not reached in practice (the acceptance is above 1/4 per try).
    return mean


@hot
def meet_stem(mats, r, m, h, vx, vy, w, ctx, rng):
    """What the next stem (``ctx[F_X]``, ``ctx[F_MAT]``) does to a rock that reaches it.

    Parameters
    ----------
    mats : ndarray, shape (n_materials, N_MAT_COLS)
    r, m : float
        Radius (m) and mass (kg) of the rock.
    h : float
        Height of the rock's centre above the ground at the stem (m).
    vx, vy, w : float
        Velocity (m/s) and spin (rad/s) there.
    ctx : ndarray
        The rock's restart context; the stems met (``F_N``) and whether a stem
        stopped the rock (``F_STOP``) are updated.
    rng : ndarray of uint64, shape (2,)
        The rock's random state; the forest draws from ``rng[STREAM]``.

    Returns
    -------
    stopped : bool
        The stem took all the rock's energy.
    vx, vy, w : float
        Velocity and spin after the stem (unchanged if it passed above).
    """
    mat = int(ctx[F_MAT])
    if h > mats[mat, M_TREE_H]:
        return False, vx, vy, w
    ctx[F_N] += 1.0
    e = 0.5 * m * (vx * vx + vy * vy) + 0.2 * m * r * r * w * w
    e_stem = stem_energy(draw_dbh(mats, mat, r, rng))
    if e <= e_stem:
        ctx[F_STOP] = 1.0
        return True, 0.0, 0.0, 0.0
    f = np.sqrt((e - e_stem) / e)
    return False, f * vx, f * vy, f * w


@hot
def stem_in_flight(px, py, pseg, seg_mat, mats, r, m, x, y, vx, vy, w, ctx, rng):
    """A flying rock whose centre is at ``x``, ``y`` (m) reaches the next stem.

    Returns whether the stem stopped it, its height ``y`` (on the centre path
    where it stopped: it drops at the foot of the stem) and its velocity
    (m/s) and spin (rad/s) after the stem; the stem after this one is placed.
    """
    k = locate(px, x, vx)
    yp = path_height(px, py, k, x)
    # The centre path lies r from the ground along the normal: r / cos(beta)
    # above it vertically on a straight piece.
    run = px[k + 1] - px[k]
    cosb = run / np.hypot(run, py[k + 1] - py[k]) if run > 0.0 else 1.0
    h = y - yp + r / cosb
    stopped, vx, vy, w = meet_stem(mats, r, m, h, vx, vy, w, ctx, rng)
    if stopped:
        return True, yp, 0.0, 0.0, 0.0
    next_stem(px, pseg, seg_mat, mats, r, x, ctx, rng)
    return False, y, vx, vy, w
