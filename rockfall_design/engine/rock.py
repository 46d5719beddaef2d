"""One rock's path from release to its end: the event loop (PHYSICS.md).

Each turn of the loop is one event: a flight to its landing (or to a barrier
on the way), or one phase of contact motion with constant accelerations to
its first event. Stations and barriers crossed on the way are recorded.
"""

from __future__ import annotations

import numpy as np

from .barriers import barrier_hit, braked_stop, meet_barrier
from .columns import (
    BR_E,
    BR_X,
    BR_YG,
    CAUGHT,
    CONTACT,
    EXIT_DOWNSLOPE,
    EXIT_UPSLOPE,
    FLIGHT,
    M_VDRAG,
    O_CAUGHT,
    O_NOT_MET,
    O_PASSED_OVER,
    O_PASSED_THROUGH_GAP,
    O_REBOUNDED,
    RS_E,
    RS_MAXX,
    RS_MODE,
    RS_MU,
    RS_MUR,
    RS_NEV,
    RS_NIMP,
    RS_SEG,
    RS_T,
    RS_VX,
    RS_VY,
    RS_W,
    RS_X,
    RS_Y,
    RUNNING,
    S_HOP_RATIO,
    S_MAX_EVENTS,
    S_V_CONTACT,
    S_V_STOP,
    STOPPED,
    UNRESOLVED,
    G,
)
from .contact import SLIP_TOL, constant_phase, contact_accel, drag_phase, start_from_rest
from .drag import along
from .flight import locate, next_landing, path_height, unit_tangent
from .forest import F_X, has_forest, meet_stem, next_stem, stem_in_flight
from .impact import collide, draw_contact
from .jit import hot
from .recording import record_passage, record_restart, traj_row
from .records import (
    N_WORK,
    REL_H,
    REL_M,
    REL_R,
    REL_ROLLING,
    REL_VX,
    REL_VY,
    REL_W,
    REL_X,
    WORK_CTX,
)


@hot
def simulate_rock(path, settings, rock, rng, stations, bars, out, resume, state0):
    """Follow one rock from its release to the end of its path.

    Parameters
    ----------
    path : Path
        The ground this rock meets: centre path of its radius, the ground
        segment under each piece, the material of each segment, the material
        table (``records.Path``).
    settings : ndarray of float, shape (N_SETTINGS,)
        ``v_contact`` (m/s), ``v_stop`` (m/s), ``max_events``, the contact
        hop ratio kappa (-).
    rock : ndarray of float, shape (N_REL_COLS,)
        The rock's row of the release table (columns ``REL_*``): radius (m),
        mass (kg), release x (m), clearance above the centre path (m),
        initial velocity (m/s), spin (rad/s), whether it starts rolling.
    rng : ndarray of uint64, shape (2,)
        The rock's random stream, and its forest's (``rng.forest_stream``).
    stations : Stations
        Stations (m), sorted, the ground height there (m), and the rows of
        ``out.cross`` and ``out.srec`` they write to (``records.Stations``).
    bars : ndarray of float, shape (B, N_BARRIER_COLS)
        Barriers (columns ``BR_*``), sorted by x; B may be 0.
    out : RockOut
        What the rock writes (``records.RockOut``, whose docstring says how
        each array must come in).
    resume : bool
        Start from ``state0`` (a row of a restart record, with ``rng`` set to
        the matching stream) instead of the release.
    state0 : ndarray of float, shape (N_RESTART_COLS,)
        The state to resume from.

    Returns
    -------
    status : int
        How the path ended (``STOPPED``, ``EXIT_*``, ``UNRESOLVED``, ``CAUGHT``);
        a rock a stem stopped is ``STOPPED`` (at the stem), with
        ``out.work[WORK_CTX + forest.F_STOP]`` set and the stems met in
        ``out.work[WORK_CTX + forest.F_N]``.
    x, y : float
        Final position of the centre (m).
    n_impacts : int
        Number of landings from flight.
    n_events : int
        Number of events.
    max_x : float
        Largest x reached by the centre (m).
    t : float
        Duration of the path (s).
    n_traj : int
        Number of rows written to ``out.traj``.
    caught_by : int
        Barrier row that caught the rock, or -1.
    """
    # The records unpacked once into the names the loop below uses (a field
    # read of a named tuple compiles to nothing; the loop is unchanged).
    px = path.px
    py = path.py
    pseg = path.pseg
    tree = path.tree
    seg_mat = path.seg_mat
    mats = path.mats
    r = rock[REL_R]
    m = rock[REL_M]
    x0 = rock[REL_X]
    h0 = rock[REL_H]
    vx0 = rock[REL_VX]
    vy0 = rock[REL_VY]
    w0 = rock[REL_W]
    spin_rolling = rock[REL_ROLLING] > 0.5
    st_x = stations.x
    st_yg = stations.yg
    st_user = stations.user
    st_srow = stations.srow
    grid_h = out.grid_h
    grid_e = out.grid_e
    grid_v = out.grid_v
    cross = out.cross
    traj = out.traj
    bar_out = out.bar_out
    bar_rec = out.bar_rec
    srec = out.srec
    srng = out.srng
    v_contact = settings[S_V_CONTACT]
    v_stop = settings[S_V_STOP]
    hop_ratio = settings[S_HOP_RATIO]
    max_events = int(settings[S_MAX_EVENTS])
    npc = px.shape[0] - 1
    drawn = out.work[:WORK_CTX]
    # Nothing drawn yet (a restart record before the first contact says so),
    # not the previous rock's draw left in the batch's scratch.
    drawn[:] = np.nan
    cur_seg = -1

    x = x0
    vx = vx0
    vy = vy0
    k = locate(px, x, vx)
    y = path_height(px, py, k, x)
    tx, ty = unit_tangent(px, py, k)
    w = -(vx * tx + vy * ty) / r if spin_rolling else w0
    t = 0.0
    n_imp = 0
    n_ev = 0
    n_traj = 0
    max_x = x
    status = RUNNING
    caught_by = -1
    nbar = bars.shape[0]
    # Barrier results, defined up front for the compiler.
    code = O_NOT_MET
    nvx = 0.0
    nvy = 0.0
    nw = 0.0
    vs = 0.0
    e_hit = 0.0  # kinetic energy (J) at the barrier that ends a flight or phase
    ctx = out.work[WORK_CTX:N_WORK]
    ctx[:] = 0.0
    if resume:
        # Continue a path from its state at a restart station.
        mode = int(state0[RS_MODE])
        x = state0[RS_X]
        y = state0[RS_Y]
        vx = state0[RS_VX]
        vy = state0[RS_VY]
        w = state0[RS_W]
        t = state0[RS_T]
        cur_seg = int(state0[RS_SEG])
        drawn[0] = state0[RS_E]
        drawn[1] = state0[RS_MU]
        drawn[2] = state0[RS_MUR]
        n_imp = int(state0[RS_NIMP])
        n_ev = int(state0[RS_NEV])
        max_x = state0[RS_MAXX]
        k = locate(px, x, vx)
        if mode == CONTACT:
            # Back onto the path (the record is exact up to round-off).
            y = path_height(px, py, k, x)
    elif h0 > 0.0:
        y += h0
        mode = FLIGHT
    else:
        vn = -vx * ty + vy * tx
        if vn > 1e-9:
            mode = FLIGHT
        elif vn < -1e-9:
            vx, vy, w, mode, cur_seg = collide(
                vx, vy, w, k, px, py, pseg, seg_mat, mats, r, v_contact, rng, drawn, hop_ratio
            )
        else:
            mode = CONTACT
            vt = vx * tx + vy * ty
            vx = vt * tx
            vy = vt * ty
    # The forest (forest.py): the next stem ahead, drawn only where there is
    # forest ahead, so that a section without one draws nothing for it. A
    # resumed rock draws it afresh (the distance to the next stem is
    # exponential, without memory, and the section may differ from the one
    # the record was made on) and counts its stems from there.
    ctx[F_X] = np.inf
    if has_forest(mats):
        next_stem(px, pseg, seg_mat, mats, r, x, ctx, rng)

    while True:
        if n_ev >= max_events:
            status = UNRESOLVED
            break
        ctx[0] = cur_seg
        ctx[1] = n_imp
        ctx[2] = n_ev
        ctx[3] = max_x
        n_ev += 1
        n_traj = traj_row(traj, n_traj, x, y, vx, vy, w, t, mode)

        if mode == FLIGHT:
            k = locate(px, x, vx)
            leaves, tf, k = next_landing(px, py, tree, x, y, vx, vy, k)
            x1 = x + vx * tf
            # A stem before the landing ends the flight there.
            stem = vx > 0.0 and ctx[F_X] < x1
            if stem:
                x1 = ctx[F_X]
                tf = (x1 - x) / vx
            # Barriers crossed by this flight, in the order of travel; the
            # first that changes the path ends the flight there.
            hit = -1
            if nbar > 0 and vx != 0.0:
                if vx > 0.0:
                    j = np.searchsorted(bars[:, BR_X], x, side="right")
                    jstep = 1
                else:
                    j = np.searchsorted(bars[:, BR_X], x, side="left") - 1
                    jstep = -1
                while 0 <= j < nbar and (bars[j, BR_X] - x1) * jstep <= 0.0:
                    ts = (bars[j, BR_X] - x) / vx
                    yb = y + vy * ts - 0.5 * G * ts * ts
                    vyb = vy - G * ts
                    hb = yb - bars[j, BR_YG]
                    code, nvx, nvy, nw = barrier_hit(bars, j, hb, vx, vyb, w, r, m, rng)
                    meet_barrier(bar_out, bar_rec, j, code, hb, vx, vyb, w, t + ts, m, r)
                    if code == O_PASSED_OVER or code == O_PASSED_THROUGH_GAP:
                        j += jstep
                        continue
                    hit = j
                    e_hit = 0.5 * m * (vx * vx + vyb * vyb) + 0.2 * m * r * r * w * w
                    break
            if hit >= 0:
                xb = bars[hit, BR_X]
                if vx > 0.0:
                    j = np.searchsorted(st_x, x, side="right")
                    while j < st_x.shape[0] and st_x[j] <= xb:
                        ts = (st_x[j] - x) / vx
                        ys = y + vy * ts - 0.5 * G * ts * ts
                        if record_passage(j, ys - st_yg[j], vx, vy - G * ts, w, t + ts, m, r,
                                   st_user, grid_h, grid_e, grid_v, cross) and st_srow[j] >= 0:
                            record_restart(st_srow[j], srec, srng, rng, drawn, ctx, FLIGHT,
                                            st_x[j], ys, vx, vy - G * ts, w, t + ts)
                        j += 1
                tb = (xb - x) / vx
                t += tb
                y = y + vy * tb - 0.5 * G * tb * tb
                x = xb
                max_x = max(max_x, x)
                if code == O_CAUGHT:
                    status = CAUGHT
                    caught_by = hit
                    # The net carries the rock on by its braking distance.
                    x, y = braked_stop(bars, hit, e_hit, vx, x, y, px, py)
                    max_x = max(max_x, x)
                    vx = 0.0
                    vy = 0.0
                    w = 0.0
                    break
                vx = nvx
                vy = nvy
                w = nw
                continue
            if vx > 0.0:
                # Stations crossed downslope by this flight, in (x, x1].
                j = np.searchsorted(st_x, x, side="right")
                while j < st_x.shape[0] and st_x[j] <= x1:
                    ts = (st_x[j] - x) / vx
                    ys = y + vy * ts - 0.5 * G * ts * ts
                    if (
                        record_passage(j, ys - st_yg[j], vx, vy - G * ts, w, t + ts, m, r,
                                st_user, grid_h, grid_e, grid_v, cross)
                        and st_srow[j] >= 0
                    ):
                        record_restart(st_srow[j], srec, srng, rng, drawn, ctx, FLIGHT,
                                        st_x[j], ys, vx, vy - G * ts, w, t + ts)
                    j += 1
            t += tf
            if stem:
                y = y + vy * tf - 0.5 * G * tf * tf
                vy -= G * tf
                x = x1
                max_x = max(max_x, x)
                stopped, y, vx, vy, w = stem_in_flight(px, py, pseg, seg_mat, mats, r, m, x, y,
                                                       vx, vy, w, ctx, rng)
                if stopped:
                    status = STOPPED
                    break
                continue
            if leaves:
                x = px[npc] if vx > 0.0 else px[0]
                y = y + vy * tf - 0.5 * G * tf * tf
                vy -= G * tf
                max_x = max(max_x, x)
                status = EXIT_DOWNSLOPE if vx > 0.0 else EXIT_UPSLOPE
                break
            x = x1
            y = path_height(px, py, k, x)
            vy -= G * tf
            max_x = max(max_x, x)
            n_imp += 1
            vx, vy, w, mode, cur_seg = collide(
                vx, vy, w, k, px, py, pseg, seg_mat, mats, r, v_contact, rng, drawn, hop_ratio
            )
            continue

        # ---- CONTACT: rolling and/or sliding on piece k ----
        seg = pseg[k]
        if seg != cur_seg:
            draw_contact(mats, seg_mat[seg], rng, drawn, r)
            cur_seg = seg
        mu = drawn[1]
        mur = drawn[2]
        tx, ty = unit_tangent(px, py, k)
        vt = vx * tx + vy * ty
        v = abs(vt)
        if v < v_stop:
            # Slow enough to be held, if the ground can hold it.
            k2, d2 = start_from_rest(px, py, k, x, y, w, r, mu, mur)
            if d2 == 0:
                status = STOPPED
                vx = 0.0
                vy = 0.0
                w = 0.0
                break
            if v <= 1e-12:
                k = k2
                tx, ty = unit_tangent(px, py, k)
                dirn = d2
                v = 0.0
            else:
                dirn = 1 if vt > 0.0 else -1
        else:
            dirn = 1 if vt > 0.0 else -1
        dx = dirn * tx
        dy = dirn * ty
        sinb = -dy
        cosb = tx
        s = -w * dirn
        # rough_soft: the ploughing drag mu_0 (v / V_s)^2 N on the translation,
        # rolling or slipping (PHYSICS.md, "The rough_soft law").
        vdr = mats[seg_mat[seg], M_VDRAG]
        qd = v * v / (vdr * vdr) if (vdr > 0.0 and mur > 0.0) else 0.0
        a, dsig, dsp, sgn, s_zero = contact_accel(sinb, cosb, v, s, mu, mur, r, qd)
        rolling = np.isnan(dsp)
        sigma = v - r * s
        if rolling or abs(sigma) <= SLIP_TOL:
            # Zero slip has no event of its own: it rolls, or the slip has
            # already been given the sense in which it grows.
            sigma = 0.0
        if s_zero and not rolling:
            s = 0.0
        # dv/dt = a - c v^2: the drag's share of a rolling rock's deceleration
        # is 5/7 of it, of a slipping rock's all of it.
        if dirn > 0:
            dist = np.hypot(px[k + 1] - x, py[k + 1] - y)
        else:
            dist = np.hypot(x - px[k], y - py[k])
        c = 0.0
        if vdr > 0.0 and mur > 0.0:
            c = (5.0 / 7.0 if rolling else 1.0) * G * cosb * mur / (vdr * vdr)
            # The drag changes v^2 over the piece by a fraction of about
            # 2 c dist. Below round-off it is no drag: its closed forms divide
            # by c, and with mu_0 near zero (hypothesis found 6e-74) they once
            # cancelled to noise that gained energy. They are written not to
            # cancel now (drag.py; a c of 1.3e-12, above this cut, was the
            # next find), and this cut keeps such a c out of them all the same.
            if c * dist < 1e-12:
                c = 0.0
        # The next event: end of piece, speed zero, slip zero, spin zero (and,
        # with the drag, a bound of rolling reached).
        if c > 0.0:
            ev, tm, ds_, v1, s1 = drag_phase(v, s, sigma, sgn, a, dsp, c, vdr, dist, sinb,
                                             cosb, mu, mur, r)
        else:
            ev, tm, ds_, v1, s1 = constant_phase(v, s, sigma, rolling, a, dsig, dsp, dist, r)
        if tm == np.inf:
            status = STOPPED
            break
        if ev == 0:
            xn = px[k + 1] if dirn > 0 else px[k]
            yn = py[k + 1] if dirn > 0 else py[k]
        else:
            xn = x + dx * ds_
            yn = y + dy * ds_
        if dirn > 0 and ctx[F_X] < xn:
            # The phase ends at the next stem (forest.py).
            dd = max((ctx[F_X] - x) / dx, 0.0)
            v1, tm = along(v, a, c, dd)
            s1 = v1 / r if rolling else s + dsp * tm
            xn = ctx[F_X]
            yn = y + dy * dd
            ev = 4
        # Barriers met in this phase, in the order of travel.
        hit = -1
        if nbar > 0:
            if dirn > 0:
                j = np.searchsorted(bars[:, BR_X], x, side="right")
            else:
                j = np.searchsorted(bars[:, BR_X], x, side="left") - 1
            while 0 <= j < nbar and (bars[j, BR_X] - xn) * dirn <= 0.0:
                dd = (bars[j, BR_X] - x) / dx
                vs, ts = along(v, a, c, dd)
                ss = vs / r if rolling else s + dsp * ts
                hb = y + dy * dd - bars[j, BR_YG]
                code, nvx, nvy, nw = barrier_hit(
                    bars, j, hb, vs * dx, vs * dy, -ss * dirn, r, m, rng)
                meet_barrier(bar_out, bar_rec, j, code, hb, vs * dx, vs * dy, -ss * dirn, t + ts,
                             m, r)
                if code == O_PASSED_OVER or code == O_PASSED_THROUGH_GAP:
                    j += dirn
                    continue
                hit = j
                e_hit = 0.5 * m * vs * vs + 0.2 * m * r * r * ss * ss
                # The phase ends at the barrier.
                xn = bars[j, BR_X]
                yn = y + dy * dd
                tm = ts
                break
        if dirn > 0 and st_x.shape[0] > 0:
            j = np.searchsorted(st_x, x, side="right")
            while j < st_x.shape[0] and st_x[j] <= xn:
                dd = (st_x[j] - x) / dx
                vs, ts = along(v, a, c, dd)
                ss = vs / r if rolling else s + dsp * ts
                if (
                    record_passage(j, y + dy * dd - st_yg[j], vs * dx, vs * dy, -ss * dirn, t + ts,
                            m, r, st_user, grid_h, grid_e, grid_v, cross)
                    and st_srow[j] >= 0
                ):
                    record_restart(st_srow[j], srec, srng, rng, drawn, ctx, CONTACT, st_x[j],
                                    y + dy * dd, vs * dx, vs * dy, -ss * dirn, t + ts)
                j += 1
        x = xn
        y = yn
        t += tm
        max_x = max(max_x, x)
        if hit >= 0:
            if code == O_CAUGHT:
                status = CAUGHT
                caught_by = hit
                x, y = braked_stop(bars, hit, e_hit, dx, x, y, px, py)
                max_x = max(max_x, x)
                vx = 0.0
                vy = 0.0
                w = 0.0
                break
            if code == O_REBOUNDED:
                # On the ground the rebound reverses the velocity along it.
                f = bars[hit, BR_E]
                vx = -f * vs * dx
                vy = -f * vs * dy
                w = nw
                if f * vs < v_stop:
                    # Too slow to leave: the rock comes to rest against the barrier.
                    status = STOPPED
                    vx = 0.0
                    vy = 0.0
                    w = 0.0
                    break
            else:
                vx = nvx
                vy = nvy
                w = nw
            continue
        vx = v1 * dx
        vy = v1 * dy
        w = -s1 * dirn
        if ev == 4:
            # On the ground the centre is r / cos(beta) above it.
            stopped, vx, vy, w = meet_stem(mats, r, m, r / abs(tx), vx, vy, w, ctx, rng)
            if stopped:
                status = STOPPED
                break
            next_stem(px, pseg, seg_mat, mats, r, x, ctx, rng)
            continue
        if ev != 0:
            continue
        # End of the piece: leave the section, fly off a convex vertex, or
        # meet the next piece (impact at a concave vertex).
        k2 = k + dirn
        if k2 < 0 or k2 >= npc:
            status = EXIT_DOWNSLOPE if dirn > 0 else EXIT_UPSLOPE
            break
        kl = k if dirn > 0 else k2
        cl = (py[kl + 1] - py[kl]) / (px[kl + 1] - px[kl])
        cr = (py[kl + 2] - py[kl + 1]) / (px[kl + 2] - px[kl + 1])
        tol = 1e-9 * (1.0 + abs(cl) + abs(cr))
        if cr < cl - tol:
            mode = FLIGHT
            continue
        k = k2
        if cr > cl + tol:
            t2x, t2y = unit_tangent(px, py, k)
            if vx * -t2y + vy * t2x < 0.0:
                vx, vy, w, mode, cur_seg = collide(
                    vx, vy, w, k, px, py, pseg, seg_mat, mats, r, v_contact, rng, drawn, hop_ratio
                )
                continue
        t2x, t2y = unit_tangent(px, py, k)
        vt = vx * t2x + vy * t2y
        vx = vt * t2x
        vy = vt * t2y

    n_traj = traj_row(traj, n_traj, x, y, vx, vy, w, t, mode)
    return status, x, y, n_imp, n_ev, max_x, t, n_traj, caught_by
