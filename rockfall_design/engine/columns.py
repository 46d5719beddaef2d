"""Codes and column layouts of the engine's plain tables.

The engine exchanges only numbers and arrays. Every table it reads or writes
(materials, settings, barriers, restart states, trajectories, crossings) is a
float64 array whose columns are named here, and every code it returns (how a
path ends, what a barrier did) is a small int named here.
"""

from __future__ import annotations

G = 9.81
"""Acceleration of gravity (m/s^2)."""

# Columns of the material table (one row per material).
M_MODEL = 0  #: impact model: 0 = spang, 1 = rn_rt, 2 = rough_soft
M_E = 1  #: e (spang) or Rn (rn_rt), mean
M_RT = 2  #: Rt (rn_rt)
M_MU = 3  #: Coulomb friction coefficient mu, mean
M_MUR = 4  #: rolling-resistance coefficient mu_r, mean
M_VSCALE = 5  #: 1 = Pfeiffer & Bowen velocity scaling of the normal restitution
M_VSK = 6  #: K of the velocity scaling (m/s)
M_ROUGH = 7  #: standard deviation of the tilt of the impact normal (rad)
M_SD_E = 8  #: standard deviation of e / Rn
M_SD_MU = 9  #: standard deviation of mu
M_SD_MUR = 10  #: standard deviation of mu_r
M_ROUGH_H = 11  #: roughness height h_r (m): one-sided tilt up to atan(h_r / r)
M_OBST = 12  #: mean obstacle height h_o (m) of the ground (rough_soft)
M_VDRAG = 13  #: speed V_s (m/s) at which the resistance has doubled (rough_soft); 0 for none
M_STEMS = 14  #: forest: stem density N (stems per m^2 of map area); 0 for no forest
M_DBH = 15  #: forest: mean stem diameter at breast height (m)
M_SD_DBH = 16  #: forest: standard deviation of the stem diameter (m)
M_TREE_H = 17  #: forest: height up to which a passing rock's centre meets a stem (m)
N_MAT_COLS = 18

MODEL_SPANG = 0
MODEL_RN_RT = 1
MODEL_ROUGH_SOFT = 2

CONTACT_HOP_RATIO = 0.1
"""kappa (-), default: a rebound whose hop is below max(h_r, kappa r) rolls on.

ILLUSTRATIVE. The rockfall literature calls rolling the motion of a block
whose bounces stay lower than its own size or the ground's asperities, a
nearly continuous contact (Dorren 2003, "modes of motion"); no published
value of the fraction of the radius was found. 0.1 r is a hop a tenth of the
block's radius, which no field observation could tell from rolling on
natural ground (PHYSICS.md, "The transition to contact").
"""

# Columns of the settings vector.
S_V_CONTACT = 0  #: outgoing normal speed below which the rock stays in contact (m/s)
S_V_STOP = 1  #: speed below which a rock that can be held is stopped (m/s)
S_MAX_EVENTS = 2  #: event limit per rock
S_HOP_RATIO = 3  #: kappa: contact height h_c = max(h_r, kappa r) a rebound must clear (-)
N_SETTINGS = 4

# How a path ends.
RUNNING = 0
STOPPED = 1
EXIT_UPSLOPE = 2  #: left the section at its upslope end (x < x_first)
EXIT_DOWNSLOPE = 3  #: left the section at its downslope end (x > x_last)
UNRESOLVED = 4  #: reached the event limit
CAUGHT = 5  #: stopped by a barrier (fence net, block of a boulder row)
STATUS_NAMES = ("running", "stopped", "exit_upslope", "exit_downslope", "unresolved", "caught")

# Barrier behaviours (see rockfall_design.plugins.measure.BarrierBehaviour).
B_NET = 0
B_RIGID = 1
B_BLOCKS = 2

# Columns of the barrier table (one row per barrier, sorted by x).
BR_X = 0  #: station (m)
BR_YG = 1  #: ground height at the station (m)
BR_H = 2  #: height of the top above ground (m)
BR_CAP = 3  #: energy capacity (J)
BR_BEH = 4  #: behaviour code
BR_E = 5  #: restitution of a rigid barrier
BR_GAP = 6  #: clear gap between blocks (m)
BR_SPACING = 7  #: block spacing (m)
BR_SEL = 8  #: a net's service energy level, SEL (J)
BR_D_SEL = 9  #: a net's elongation in its SEL test (m); 0 for none given
BR_D_MEL = 10  #: a net's maximum elongation in its MEL test (m); 0: no braking distance
N_BARRIER_COLS = 11

# Outcome of a rock's first meeting with a barrier (rockfall_design.plugins.measure.Outcome).
O_NOT_MET = 0
O_CAUGHT = 1
O_PASSED_OVER = 2
O_BROKEN_THROUGH = 3
O_REBOUNDED = 4
O_PASSED_THROUGH_GAP = 5
N_OUTCOMES = 6

# Columns of a rock's state at the first downslope passage of a restart station,
# enough to resume the path there exactly as it would have gone on (with the
# rock's random stream, saved apart as uint64).
RS_MODE, RS_X, RS_Y, RS_VX, RS_VY, RS_W, RS_T = 0, 1, 2, 3, 4, 5, 6
RS_SEG, RS_E, RS_MU, RS_MUR, RS_NIMP, RS_NEV, RS_MAXX = 7, 8, 9, 10, 11, 12, 13
N_RESTART_COLS = 14

# Columns of the record of a rock's first meeting with a barrier.
BM_H, BM_V, BM_E, BM_T = 0, 1, 2, 3
N_BMEET_COLS = 4

FLIGHT = 0
CONTACT = 1

# Columns of a recorded trajectory point.
T_X, T_Y, T_VX, T_VY, T_W, T_T, T_MODE = 0, 1, 2, 3, 4, 5, 6
N_TRAJ_COLS = 7

# Columns of the per-station detail record.
C_H, C_VX, C_VY, C_W, C_T = 0, 1, 2, 3, 4
N_CROSS_COLS = 5
