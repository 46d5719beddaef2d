"""Impacts: Newton restitution with Coulomb friction and spin, or the lumped-mass law.

PHYSICS.md, 'Impact'. ``collide`` draws the material's parameters for the
impact, applies :func:`impact` and decides between flight and contact.
"""

from __future__ import annotations

import numpy as np

from .columns import (
    CONTACT,
    FLIGHT,
    M_E,
    M_MODEL,
    M_MU,
    M_MUR,
    M_OBST,
    M_ROUGH,
    M_ROUGH_H,
    M_RT,
    M_SD_E,
    M_SD_MU,
    M_SD_MUR,
    M_VDRAG,
    M_VSCALE,
    M_VSK,
    MODEL_RN_RT,
    MODEL_ROUGH_SOFT,
    G,
)
from .flight import unit_tangent
from .jit import hot
from .rng import next_normal, next_uniform, truncated_normal


@hot
def impact(vx, vy, w, nx, ny, r, model, e, rt, mu, vscale, vsk, rough, rng, tilt_max=0.0,
           mur=0.0, vdrag=0.0):
    """Velocity and spin after an impact on ground of outward normal (nx, ny).

    Parameters
    ----------
    vx, vy : float
        Velocity before the impact (m/s).
    w : float
        Angular velocity before (rad/s), counter-clockwise positive.
    nx, ny : float
        Unit outward normal of the ground (centre path piece).
    r : float
        Rock radius (m).
    model : int
        ``MODEL_SPANG``, ``MODEL_RN_RT`` or ``MODEL_ROUGH_SOFT``.
    e : float
        Coefficient of restitution e (spang) or Rn (rn_rt), this impact's draw.
    rt : float
        Tangential restitution Rt (rn_rt only).
    mu : float
        Coulomb friction coefficient, this impact's draw.
    vscale : bool
        Apply the Pfeiffer & Bowen (1989) scaling e / (1 + (|v_n| / K)^2).
    vsk : float
        K of that scaling (m/s), 9.144 m/s in CRSP.
    rough : float
        Standard deviation of the tilt of the impact normal (rad).
    rng : ndarray of uint64, shape (1,)
        The rock's random stream (for the tilt).
    tilt_max : float
        Largest one-sided tilt of the normal (rad), atan(h_r / r) for a
        roughness height h_r; 0 for none.
    mur : float
        Rolling resistance mu_0 of this impact's draw (-), rough_soft only.
    vdrag : float
        Speed V_s (m/s) at which the resistance has doubled, rough_soft
        only; 0 for a resistance that does not grow with the speed.

    Returns
    -------
    vx, vy, w : float
        Velocity (m/s) and angular velocity (rad/s) after the impact.

    Notes
    -----
    With v_n = v.n < 0, v_t = v.t, slip u = v_t + r w, normal impulse per
    unit mass p_n = (1 + e)|v_n| (Spang & Rautenstrauch 1988; PHYSICS.md):

    * spang, stick (|u| <= 7/2 mu p_n): v_t' = (5 v_t - 2 r w) / 7,
      w' = -v_t' / r;
    * spang, slip: v_t' = v_t - mu p_n sgn(u), w' = w - 5/2 mu p_n sgn(u) / r;
    * rough_soft: first the ploughing drag slows the tangential velocity,
      v_t <- v_t / (1 + mu_0 p_n |v_t| / V_s^2), and the resistance moment
      takes min(|w|, 5/2 mu_0 p_n / r) of the spin, then as spang
      (PHYSICS.md, "The rough_soft law"); spang and rn_rt impacts take no
      rolling resistance;
    * rn_rt: v_n' = -Rn v_n, v_t' = Rt v_t and w' = Rt w (PHYSICS.md,
      "Lumped-mass law"): the spin scales with the tangential speed, so a
      rolling rock stays rolling and no energy is gained.

    A tilted normal that would make the rock arrive from below is drawn again
    (at most 64 times, then the untilted normal is used).

    Roughness as a height (PlatRock's convention, PHYSICS.md "Options"): the
    normal also turns by an angle drawn uniformly from [0, ``tilt_max``],
    always against the tangential velocity, as if the rock met the face of an
    asperity of height h_r turned towards it; larger rocks (larger r) feel a
    smaller tilt. Turning against the motion makes the arrival steeper, so it
    never makes the rock arrive from below.
    """
    mx = nx
    my = ny
    # One-sided tilt: counter-clockwise turns the normal towards -t, against
    # a rock moving along +t (t = (n_y, -n_x)).
    th_h = 0.0
    if tilt_max > 0.0:
        vt0 = vx * ny - vy * nx
        if vt0 != 0.0:
            th_h = tilt_max * next_uniform(rng) * (1.0 if vt0 > 0.0 else -1.0)
            c = np.cos(th_h)
            s = np.sin(th_h)
            mx = c * nx - s * ny
            my = s * nx + c * ny
    if rough > 0.0:
        for _ in range(64):
            th = th_h + rough * next_normal(rng)
            c = np.cos(th)
            s = np.sin(th)
            ax = c * nx - s * ny
            ay = s * nx + c * ny
            if vx * ax + vy * ay < 0.0:
                mx = ax
                my = ay
                break
    tx = my
    ty = -mx
    vn = vx * mx + vy * my
    vt = vx * tx + vy * ty
    if vn >= 0.0:
        return vx, vy, w
    ee = e
    if vscale:
        q = vn / vsk
        ee = e / (1.0 + q * q)
    vn2 = -ee * vn
    if model != MODEL_RN_RT:
        pn = -(1.0 + ee) * vn
        # rough_soft only: the ground resists in an impact as in contact
        # (PHYSICS.md, "The rough_soft law"). Its ploughing drag
        # mu_0 (v_t / V_s)^2 N acts on the translation: over the normal
        # impulse p_n, dv_t / dp = -mu_0 v_t^2 / V_s^2, integrated exactly,
        # which slows v_t without ever reversing it. Its resistance moment
        # mu_0 N r takes the angular impulse mu_0 r p_n from the spin, at most
        # stopping it. The spang law keeps its impact as published (Spang &
        # Rautenstrauch 1988): its impacts take no rolling resistance.
        if model == MODEL_ROUGH_SOFT and vdrag > 0.0 and mur > 0.0:
            vt = vt / (1.0 + mur * pn * abs(vt) / (vdrag * vdrag))
        if model == MODEL_ROUGH_SOFT and mur > 0.0 and w != 0.0:
            dw = 2.5 * mur * pn / r
            if abs(w) <= dw:
                w = 0.0
            else:
                w = w - dw if w > 0.0 else w + dw
        u = vt + r * w
        if abs(u) <= 3.5 * mu * pn:
            vt2 = (5.0 * vt - 2.0 * r * w) / 7.0
            w2 = -vt2 / r
        else:
            sg = 1.0 if u > 0.0 else -1.0
            vt2 = vt - mu * pn * sg
            w2 = w - 2.5 * mu * pn * sg / r
    else:
        vt2 = rt * vt
        w2 = rt * w
    return vn2 * mx + vt2 * tx, vn2 * my + vt2 * ty, w2


@hot
def draw_contact(mats, mat, rng, drawn, r):
    """Draw this contact's e, mu and mu_r for material ``mat`` into ``drawn``.

    For rough_soft, mu_r is the resistance at low speed of a rock of radius
    ``r`` (m): the soil's own, drawn, plus h_o / (h_o + r) from the ground's
    obstacles of mean height h_o (PHYSICS.md, "The rough_soft law").
    """
    drawn[0] = truncated_normal(rng, mats[mat, M_E], mats[mat, M_SD_E], 0.0, 1.0)
    drawn[1] = truncated_normal(rng, mats[mat, M_MU], mats[mat, M_SD_MU], 0.0, np.inf)
    drawn[2] = truncated_normal(rng, mats[mat, M_MUR], mats[mat, M_SD_MUR], 0.0, np.inf)
    if int(mats[mat, M_MODEL]) == MODEL_ROUGH_SOFT:
        ho = mats[mat, M_OBST]
        drawn[2] += ho / (ho + r)


@hot
def collide(vx, vy, w, k, px, py, pseg, seg_mat, mats, r, v_contact, rng, drawn,
             hop_ratio=0.0):
    """Impact on piece ``k``, then decide between flight and contact.

    Draws the material parameters of the piece (per impact), applies
    :func:`impact`, and returns (vx, vy, w, mode, seg). The rock flies again
    only if its rebound clears the contact height: its hop above the piece,
    v_n'^2 / (2 g n_y), n the piece's outward normal, must reach
    h_c = max(h_r, ``hop_ratio`` r), h_r the ground's roughness height (m);
    and its outgoing normal speed must reach ``v_contact`` (m/s), a numerical
    floor. Otherwise the normal component is removed and the rock continues
    in contact (PHYSICS.md, "The transition to contact").
    """
    seg = pseg[k]
    mat = seg_mat[seg]
    draw_contact(mats, mat, rng, drawn, r)
    tx, ty = unit_tangent(px, py, k)
    nx = -ty
    ny = tx
    vx, vy, w = impact(
        vx,
        vy,
        w,
        nx,
        ny,
        r,
        int(mats[mat, M_MODEL]),
        drawn[0],
        mats[mat, M_RT],
        drawn[1],
        mats[mat, M_VSCALE] > 0.5,
        mats[mat, M_VSK],
        mats[mat, M_ROUGH],
        rng,
        np.arctan(mats[mat, M_ROUGH_H] / r),
        drawn[2],
        mats[mat, M_VDRAG],
    )
    vn = vx * nx + vy * ny
    # A hop lower than the ground's asperities or a small fraction of the
    # block is rolling, not bouncing; with hop_ratio 0 (and no roughness
    # height) v_contact alone decides, as before the criterion.
    h_c = max(mats[mat, M_ROUGH_H], hop_ratio * r) if hop_ratio > 0.0 else 0.0
    if vn >= v_contact and vn * vn >= 2.0 * G * ny * h_c:
        return vx, vy, w, FLIGHT, seg
    vt = vx * tx + vy * ty
    return vt * tx, vt * ty, w, CONTACT, seg
