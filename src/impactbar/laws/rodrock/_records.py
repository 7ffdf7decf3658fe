"""The slots of the exact blow's records (:mod:`impactbar.laws.rodrock._exactloop`'s workspace, made by
:func:`impactbar.laws.rodrock.exact._workspace`; the tangent run's ``TCUR``) and of the lattice
blow's (:mod:`impactbar.laws.rodrock._rockloop`, ``_rocktangent``): one name per slot, read
by the compiled kernels as compile-time constants (numba freezes a module's integer globals), so
that a slot is found by its name and never by its number.

A record's constants share its name as their prefix (``PR_MASS`` is a slot of ``PR``); ``*_SIZE``
is the record's length. Slots not named here are unused. Numba's cache does not follow these
values into the kernels that read them: a change here wants the package's ``__pycache__`` cleared.
"""

# -- the workspace tuple ``ws`` (its order: the kernels unpack it whole) ----------------------------
WS_PF = 0  # PF, the pieces' floats (the pool: its rows its capacity)
WS_PI = 1  # PI, the pieces' links and term ranges
WS_TK = 2  # TK, the terms' keys (the pool's terms: its size their capacity)
WS_TC = 3  # TC, the terms' coefficients
WS_CNT = 4  # CNT, the pool's counts
WS_CHI = 5  # CHI, the channels' last pieces and receivers' cursors
WS_LAM = 8  # lam, the exponent table
WS_PR = 13  # PR, the blow's parameters
WS_SZ = 14  # SZ, the segments' impedances
WS_ST = 15  # ST, the segments' travel times
WS_NSF = 16  # NSF, the nodes' float state
WS_NSI = 17  # NSI, the nodes' cursors and the contact flag
WS_BS = 18  # BS, the bit's and the rock's state
WS_BI = 19  # BI, the bit's branch and episode count
WS_RT = 20  # RT, the branches' roots
WS_RC = 21  # RC, the roots' indices in the exponent table
WS_RD = 22  # RD, the switch log
WS_EP = 23  # EP, the loading episodes
WS_CI = 24  # CI, the run's status and counters
WS_CT = 25  # CT, the run's times and energies

# -- the tangent run's tuple ``tg`` (its order: the kernels unpack it whole) ---------------------
TG_IT = 0  # IT, the impulses' times
TG_IW = 1  # IW, their weights
TG_IJ = 2  # IJ, their jumps
TG_IN = 3  # IN, their links
TG_ICH = 4  # ICH, the channels' first and last impulses
TG_TCUR = 5  # TCUR, the store's counts and the schedule's cursors

# -- HMAX: a history's largest value (``_exacthistory.history_max``'s ``res``, float64) ------------
HMAX_SIZE = 2
HMAX_V = 0  # the largest value
HMAX_T = 1  # when first reached

# -- PR: the blow's parameters (float64) ---------------------------------------------------------
PR_SIZE = 32
PR_K = 0  # the rock's loading stiffness k
PR_KU = 1  # its unloading stiffness k_u
PR_MASS = 2  # the bit's mass m (0: the massless bit)
PR_FEED = 3  # the feed force f (0 in a tangent run)
PR_ZBIT = 4  # the impedance at the bit (the rod's last segment's)
PR_H = 5  # h, the shortest travel time (written, not read: PR_WINDOW holds the same h)
PR_FIXED = 6  # 1: a fixed horizon (run to t_max, certify nothing)
PR_SEMI = 7  # 1: a semi-infinite rod (the bit's reflected wave leaves the chain)
PR_LB = 8  # Lb, the time scale on which terms are pruned (max(2 sum T, h))
PR_SPENT = 9  # the fraction of the available energy below which the blow is spent
PR_E0 = 10  # the piston's energy at impact
PR_CROD = 11  # the rod's static compliance C_rod
PR_CP = 12  # the piston's compliance about its struck end
PR_CSHANK = 13  # the rod's compliance about the shank (the bit's mass at its far side)
PR_CBIT = 14  # the rod's compliance about the bit
PR_MP = 15  # the piston's mass
PR_MR = 16  # the rod's mass with the bit's
PR_WINDOW = 17  # h, the window's length (the same value as PR_H)
PR_TMAX = 18  # t_max (inf: none)
PR_MAXWIN = 19  # the most windows (the cost bound)
PR_P0 = 20  # f/k, the bit's penetration at the start (written, not read by the kernels)
PR_NP = 21  # the contact node's index: the piston's segment count
PR_DRIVEN = 22  # 1: a drive at the piston's far end
PR_RECORD = 23  # 1: keep the force and penetration histories
PR_MAXP = 24  # the most pieces (the cost bound)
PR_NODW = 25  # 1: the drive's work is not wanted (a tangent run)

# -- BS: the bit's and the rock's state (float64) -------------------------------------------------
BS_SIZE = 16
BS_P = 0  # p, the bit's penetration
BS_X = 1  # x = p - ref, from the branch's reference (0 loading, p_perm else)
BS_W = 2  # w = p', the bit's velocity
BS_PMAX = 3  # p_max, the largest penetration
BS_RMAX = 4  # R_max = k p_max
BS_PPERM = 5  # p_perm = p_max - R_max/k_u
BS_DISS = 6  # the work the rock dissipated
BS_RDP = 7  # int R dp, the rock's work
BS_ABS = 8  # the energy a semi-infinite rod absorbed (radiated)
BS_PSTART = 9  # p at the start
BS_TPMAX = 10  # when p_max was reached
BS_EPT = 11  # the loading episode's start time
BS_EPP = 12  # the loading episode's start penetration
BS_DRIVEW = 14  # the drive's work on the piston

# -- BI: the bit's branch and the episodes (int64) ------------------------------------------------
BI_SIZE = 4
BI_BRANCH = 0  # the rock's branch (LOAD, ELASTIC, FREE)
BI_NEP = 1  # loading episodes ended (EP holds the first of them)

# -- CI: the run's status and counters (int64) ----------------------------------------------------
CI_SIZE = 8
CI_STATUS = 0  # 0 done, 1 the pool full (again, larger); a tangent run's 2 and 3 (t_run)
CI_END = 1  # how the blow ended (SEPARATED, ... of _exactpieces)
CI_WIN = 2  # windows done
CI_GIVEUP = 4  # crossing searches given up
CI_SEP = 5  # separations of piston and shank
CI_RECON = 6  # re-contacts
CI_DEG = 7  # series that reached the degree limit

# -- CT: the run's times and energies (float64; CT_PP .. CT_THR by account) -----------------------
CT_SIZE = 16
CT_T = 0  # the time reached
CT_TSEP = 1  # the last separation
CT_TLOAD = 2  # the last loading episode's end
CT_PP = 3  # the piston's momentum
CT_EP = 4  # the piston's energy
CT_PR = 5  # the rod's momentum
CT_ER = 6  # the rod's wave energy
CT_PSI = 7  # Psi, the energy of rod, bit and rock above the static state
CT_THR = 8  # the energy a new yield of the rock needs
CT_TACC = 9  # the time of account's last pass (NaN: none yet)

# -- CNT: the pool's counts (int64; the tangent's template CNT0 alike) -----------------------------
CNT_SIZE = 4
CNT_PIECES = 0  # pieces stored
CNT_TERMS = 1  # terms stored
CNT_FULL = 3  # 1: the pieces, the terms or the episodes overflowed

# -- TCUR: the tangent run's impulse store and schedule (int64) ----------------------------------
TCUR_SIZE = 7
TCUR_N = 0  # impulses stored
TCUR_FULL = 1  # 1: the impulses' store is full
TCUR_CONTACT = 2  # the contact's cursor in the schedule (RD's rows)
TCUR_BIT = 3  # the bit's cursor in the schedule
TCUR_FAIL = 4  # 1 a grazing re-contact, 2 the branches out of step, 3 a switch met by an impulse
TCUR_SEPS = 5  # separations a moving step set off
TCUR_UNLOADS = 6  # unloadings a moving step set off

# -- RD: the switch log (complex) -------------------------------------------------------------------
RD_HEAD = 0  # the header row: its RD_ROWS the rows written, its RD_FULL 1 once full

# -- NSF, NSI: the nodes' state, a row each (0 the piston's far end, n_p the contact, J the bit) ---------
NSF_GAP = 0  # the gap at the node (piston to shank at the contact; 0 while in contact)
NSF_SHANK = 1  # the shank's displacement at the contact node
NSF_COLS = 4
NSI_IN = 0  # the cursor of the first wave in last loaded (f at a junction and the bit, g at the far end)
NSI_IN2 = 1  # the cursor of the second wave in (g at a junction)
NSI_DRIVE = 2  # the drive's cursor (the far end's row)
NSI_CONTACT = 3  # 1 the node in contact (welded), 0 apart
NSI_COLS = 4

# -- RD's rows after its header: a switch each; its three values by the switch's code ---------------
RD_ROWS = 0  # the header's count of rows written (RD[RD_HEAD, RD_ROWS])
RD_FULL = 1  # the header's 1 once the log is full (RD[RD_HEAD, RD_FULL])
RD_T = 0  # the switch's time
RD_CODE = 1  # its code (LOG_SEP, LOG_RECON, LOG_BIT + the new branch of _exactnode)
RD_V1 = 2  # its first value: a re-contact's force just after, a separation's f arriving, the bit's p'
RD_V2 = 3  # its second: a re-contact's jump of the shank's velocity, a separation's g arriving
RD_V3 = 4  # its third: a re-contact's gap rate just before
RD_COLS = 6
# the three values by the switch's code, as the tangent reads them
SEP_F, SEP_G = RD_V1, RD_V2  # a separation's: the waves f and g arriving just before it
RECON_FORCE, RECON_JUMP, RECON_GAPRATE = RD_V1, RD_V2, RD_V3  # a re-contact's (as RD_V1 .. RD_V3 say)
BITLOG_PDOT = RD_V1  # the bit's switch: p' just before it (a massless bit)

# -- RT, RC: the rock's branches' roots, a row per branch (LOAD, ELASTIC, FREE) -------------------
RT_FIRST = 0  # the first root (the only one with a massless bit)
RT_SECOND = 1  # the second (0 with a massless bit)
RC_FIRST = 0  # the first root's index in the exponent table
RC_SECOND = 1  # the second's

# -- EP: the loading episodes, a row each ----------------------------------------------------------
EP_TSTART = 0  # the episode's start time
EP_TEND = 1  # its end time
EP_PSTART = 2  # the penetration at its start
EP_PEND = 3  # at its end
EP_DISS = 4  # the work it dissipated in the rock
EP_COLS = 5

# -- STK: the branch and bound's stack of intervals (a piece's largest value, its first zero) ------
STK_A = 0  # the interval's start
STK_B = 1  # its end
STK_FA = 2  # the piece's value at the start (a zero's search only)
STK_FB = 3  # at the end
STK_COLS = 4

# -- IMP, END: the tangent batch's impulses sent and the end state of each direction ----------------
IMP_DIR = 0  # the direction the impulse belongs to
IMP_T = 1  # its time
IMP_W = 2  # its weight
IMP_JUMP = 3  # the primal's step it differentiates
IMP_COLS = 4
END_SHANK = 0  # the shank's displacement at the contact node
END_GAP = 1  # the gap there
END_PPERM = 2  # the rock's permanent penetration
END_SEPS = 3  # separations a moving step set off
END_UNLOADS = 4  # unloadings a moving step set off
END_COLS = 5

# -- WB, WN: the scratch blocks (each the coefficients B[e, d] and counts N[e] of one piece) -------
BLOCKS = 16
B_IN = 0  # the first wave in: f_in at a junction and the contact, F at the bit, the drive at the far end
B_IN2 = 1  # the second wave in: g_in (at the piston's far end, the wave arriving there)
B_OUT = 2  # the wave a node emits: f_out, the far end's, the bit's reflected G
B_OUT2 = 3  # a junction's second wave out, g_out (scratch of the drive's work, of the absorbed wave)
B_N = 4  # the node's force N (the bit's penetration where recorded)
B_RATE = 5  # a rate: the common velocity, the gap's rate; the bit's forcing over Z or m
B_E = 6  # the bit's forcing E = 2 F + f
B_X = 7  # the bit's x
B_XD = 8  # the bit's x'
B_ZERO = 9  # the piece whose first zero is searched (the gap, the bit's switch)
B_EMIT = 10  # emit's scratch
B_ODE = 11  # the bit's first-order stage (x' - r_2 x, with a mass)
B_AUX = 12  # a piece loaded apart (the energies, the pieces before a separation)
B_SCR1 = 13  # the crossing search's three scratch blocks
B_SCR2 = 14
B_SCR3 = 15

# -- PF, PI: the wave-piece pool's pieces, a row each (float64 and int64 columns) -------------------
PF_START = 0  # the piece's start (emission) time
PF_VALID = 1  # the time up to which its series holds (inf: a closed form)
PF_REF = 2  # its reference time (its exponentials' origin)
PF_INT = 3  # its integral over the span L, cached (NaN until computed)
PF_INT2 = 4  # the integral of its square over L, cached (NaN until computed)
PF_COLS = 5
PI_NEXT = 0  # the next piece of its channel (-1: none)
PI_TERMS = 1  # its first term in the terms' arrays TK, TC
PI_COUNT = 2  # its count of terms
PI_FLAG = 3  # its flag (what emitted it)
PI_COLS = 4
# -- CHI: each channel's list of pieces (int64 columns; the tangent's impulse queues ICH alike) ------
CHI_TAIL = 0  # its last piece (the next one emitted follows it; -1: none)
CHI_HEAD = 1  # its receiver's cursor: the first piece not yet read (a history's: its first piece)
ICH_TAIL = 0  # an impulse queue's last entry
ICH_HEAD = 1  # its first entry not yet taken (-1: empty)

# -- the tangent batch's ``out`` (K, n_p, M, 2): the piston's waves' integrals against its modes ------
OUT_F = 0  # of the piston's wave F
OUT_G = 1  # of its wave G
OUT_COLS = 2

# -- the chain's ends and the exponent table ------------------------------------------------------
SEG_FAR = 0  # the piston's driven-end segment (SZ, ST count from the piston's far end)
CH_FAR_OUT = 0  # the channel of the wave leaving the piston's far end (f of segment 1)
CH_FAR_IN = 1  # the channel of the wave arriving there (g of segment 1)
E_CONST = 0  # the exponent table's first entry: 0, the constants'

# == the lattice blow's records (:mod:`impactbar.laws.rodrock._rockloop`, ``_rocktangent``) =======
# not the exact blow's: its bit (``BIT``) keeps the branch among its floats and no ``x`` (``BS``)

# -- BIT: the bit's and the rock's state ``bs`` (float64; the tangent's ``dbs`` rows alike) ---------
BIT_SIZE = 7
BIT_P = 0  # p, the bit's penetration
BIT_W = 1  # w = p', the bit's velocity
BIT_BRANCH = 2  # the rock's branch (LOAD, ELASTIC, FREE of _rockloop, as floats; no tangent)
BIT_PMAX = 3  # p_max, the largest penetration
BIT_RMAX = 4  # R_max = k p_max
BIT_PPERM = 5  # p_perm = p_max - R_max/k_u
BIT_WORK = 6  # the work done on the rock

# -- BITREC: the bit's record, a row per step (float64) -----------------------------------------------
BITREC_FORCE = 0  # the rock's force
BITREC_PEN = 1  # the bit's penetration
BITREC_COLS = 2
JUNC_SHANK = 0  # the junction forces' first column (a column per junction): the shank's, piston on rod

# -- BITP: the bit's parameters ``bp`` (float64) ------------------------------------------------------
BITP_SIZE = 5
BITP_Z = 0  # the impedance at the bit (the rod's last cell's)
BITP_K = 1  # the rock's loading stiffness k
BITP_KU = 2  # its unloading stiffness k_u
BITP_MASS = 3  # the bit's mass m (0: the massless bit)
BITP_FEED = 4  # the feed force f

# -- CTRL: the loop's controls ``ctrl`` (float64; the tangent's loop reads the first two) ------------
CTRL_SIZE = 9
CTRL_DT = 0  # the step, the cells' travel time
CTRL_STOP = 1  # the energy below which a separated blow ends
CTRL_QUIET = 2  # steps separated after which the blow ends (0: never)
CTRL_GAP = 3  # the piston-shank gap at the start
CTRL_FREE = 4  # 1: end where the piston is free for good (under a drive, theory §11); 0: never
CTRL_LOCATE = 5  # 1: the contact's switches inside their steps (``BlowGrid.locate``); 0: at their ends
CTRL_HELD = 6  # with CTRL_LOCATE, 1: the waves arriving at the contact on the step before the start
CTRL_FA = 7  # are held in CTRL_FA (F)
CTRL_GA = 8  # and CTRL_GA (G); 0: none (the blow's first step)

# -- ACC: the loop's accounts ``acc`` (float64, written by the loop) ----------------------------------
ACC_SIZE = 9
ACC_USHANK = 0  # the shank's displacement
ACC_LOSS = 1  # the energy the grid lost (the bit's average against its exact step)
ACC_STEPS = 2  # the steps run
ACC_ENDED = 3  # how the blow ended: 0 t_max, 1 the energy, 2 separated
ACC_GAP = 4  # the piston-shank gap at the end
ACC_WORK = 5  # the drive's work on the piston
ACC_HELD = 6  # CTRL_HELD, CTRL_FA, CTRL_GA at the end (a blow run on in chunks)
ACC_FA = 7
ACC_GA = 8

# -- TSCR: the bit's tangent step's scratch rows (``bit_step_tangent``'s ``scratch``, (5, nv)) -------
TSCR_SIZE = 5
TSCR_LEFT = 0  # the tangent of the step's time left
TSCR_TAU = 1  # the tangent of the sub-step's length
TSCR_P0 = 2  # the tangent of p at the sub-step's start
TSCR_REF = 3  # the tangent of the branch's reference p_ref

# -- CELL: the rows of the tangent loop's piston cells ``P`` (3, n_p) and their tangents ``dP`` -------
CELL_SIZE = 3
CELL_F = 0  # F, the waves running toward the shank
CELL_G = 1  # G, the waves running back
CELL_Z = 2  # Z, the cells' impedances (dP's: the directions)
