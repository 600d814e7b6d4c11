"""Sensor error models of the drive simulator: IMU, wheel speeds (odometer), GNSS.

Every function takes the exact truth of tools/sim/trajectory.py (duck typed: only the
field names below are used) and returns what the sensor would report, with errors drawn
from a seeded ``numpy.random.Generator`` (``SeedSequence(seed)``, one independent child
stream per error component, so switching one component off does not change the others).
No module state; units in every name. Frames (docs/frames.md): ENU navigation frame; body
x right, y forward, z up; heading clockwise from north.

Truth fields used: ``t_s``, ``dtheta_b_rad``, ``dv_b_mps`` (IMU, rows k = increments over
(t_{k-1}, t_k], row 0 zero); ``speed_mps`` (signed, along body y), ``yaw_rate_rps``
(heading rate, clockwise/right turn positive) (odometer); ``lat_rad``, ``lon_rad``,
``h_m``, ``v_enu_mps``, ``outages`` (GNSS).

IMU — seed 003's model on increments
====================================
Seed 003 (continuous form)::

    f~ = b_a + M_a f + w_a,     w~ = b_g + M_g w + G_g f + w_g

integrated over one sample interval dt (b constant over the interval, noise white)::

    dv~     = M_a dv     + b_a dt                + n_a,   n_a ~ N(0, (N_a^2) dt)
    dtheta~ = M_g dtheta + b_g dt + G_g dv       + n_g,   n_g ~ N(0, (N_g^2) dt)

``M = I + diag(scale factors) + misalignments (off-diagonal, non-orthogonal axes)``,
``b = b_turn_on + b_in_run(t)``. N_a is the accelerometer noise density converted
µg/√Hz -> m/s²/√Hz (× 9.80665e-6; numerically equal to the velocity random walk in
m/s/√s), N_g the gyro angle random walk °/√h -> rad/√s (× π/180 / 60). The per-sample
increment noise std is therefore N·√dt, the rate noise std N/√dt, and the Allan
deviation of the rate N/√τ (IEEE Std 952-1997, annex C: ARW N = σ_A(τ = 1 s)).

In-run bias instability: first-order Gauss-Markov process per axis,
``db/dt = -b/T + w``, steady-state std σ_GM, correlation time T, simulated by its exact
discretisation ``b_k = a b_{k-1} + σ_GM √(1-a²) ξ_k``, ``a = exp(-dt/T)``, started in
steady state. Its Allan variance (IEEE Std 952-1997 annex C; El-Sheimy, Hou, Niu,
"Analysis and modeling of inertial sensors using Allan variance", IEEE TIM 57(1), 2008,
table I, "correlated noise"), with x = τ/T::

    σ_A²(τ) = (2 σ_GM² / x) · [1 - (3 - 4 e^{-x} + e^{-2x}) / (2x)]

rises like √τ (rate random walk) for τ ≪ T, falls like 1/√τ (white) for τ ≫ T, and peaks
at τ = 1.893 T with **σ_A,max = 0.6174 σ_GM** (:data:`GM_ADEV_PEAK_FACTOR`, computed
below from the formula). A spec's ``*_bias_instability_*`` is the Allan-deviation floor
(the datasheet number); we set ``σ_GM = bias_instability / 0.6174`` so that the GM's
Allan maximum equals it. Note: the often-quoted 0.664 = √(2 ln2/π) is a different
relation — the flicker (1/f) floor σ_A = 0.664 B of IEEE 952's bias-instability
coefficient B; a single GM has a bump, not a flat floor, and its peak factor is 0.6174.

Mounting: the IMU's sensor frame s is rotated relative to the body by (roll, pitch, yaw)
in the body's own Euler convention (docs/frames.md, 3-1-2):
``C_bs = Rz(-yaw) Rx(pitch) Ry(roll)``, yaw clockwise positive. The sensor outputs are
``C_sb = C_bs^T`` times the exact body increments (exact for a fixed rotation), before the
errors. A firmware that takes the sensor frame for the body then sees the heading of the
sensor's y axis, i.e. H + yaw.

Presets (seed 003 Table 1; 1-sigma per axis; "turn-on" = run-to-run constant drawn per
seed; "BI" = in-run Allan floor; misalignment per off-diagonal element; G_g per element):

======== ======== ======= ======= ===== ====== ======== ======== ======= ===== ====== ======== =====
grade    acc bias acc BI  acc n.  acc   acc    gyro b.  gyro BI  ARW     gyro  gyro   G_g      T_GM
         m/s²     m/s²    µg/√Hz  SF    mis.   rad/s    °/h      °/√h    SF    mis.   °/h/g    s
                                  ppm   mrad   (°/h)                     ppm   mrad
======== ======== ======= ======= ===== ====== ======== ======== ======= ===== ====== ======== =====
marine   1e-4     1e-5    10      20    0.01   5e-9     0.0005   0.001   5     0.01   0        300
                                               (0.001)
aviation 5e-4     5e-5    20      100   0.025  5e-8     0.005    0.002   10    0.025  0        300
                                               (0.0103)
interm.  3e-3     3e-4    50      300   0.1    5e-7     0.05     0.01    100   0.1    0        300
                                               (0.103)
mid-     1e-3     1e-4    20      100   0.05   7.27e-8  0.005    0.003   50    0.05   0        300
grade                                          (0.015)
tactical 3e-2     3e-3    300     500   0.5    5e-6     0.5      0.05    300   0.5    2        100
                                               (1.03)
automot. 0.2      2e-2    1500    5000  5      1e-3     20       2       10000 5      180      100
                                               (206)
perfect  0        0       0       0     0      0        0        0       0     0      0        -
======== ======== ======= ======= ===== ====== ======== ======== ======= ===== ====== ======== =====

Why these values:

* Table 1 columns, taken as the turn-on (run-to-run) bias and the white noise: single
  values used as given (marine/aviation/intermediate/tactical gyro bias, aviation noise);
  ranges: geometric middle rounded (aviation accel bias 3e-4..1e-3 -> 5e-4; intermediate
  1e-3..1e-2 -> 3e-3, noise 20..100 -> 50 µg/√Hz, ARW 0.002..0.03 -> 0.01 °/√h; tactical
  accel bias 1e-2..1e-1 -> 3e-2, noise 100..1000 -> 300 µg/√Hz); open-ended: marine
  "< 20 µg/√Hz" -> 10 (quartz/pendulous navigation accelerometer) and "< 0.002 °/√h" ->
  0.001 (large RLG); automotive "> 1e-1" -> 0.2 m/s² (~20 mg, consumer MEMS offset),
  "> 5e-4 rad/s" -> 1e-3 (≈ 200 °/h after factory trim), "> 1000 µg/√Hz" -> 1500,
  "> 1 °/√h" -> 2 (2x the class limit, like the table's other steps).
* Tactical ARW 0.05 °/√h is inside 0.03..1 (the quiet end; HG1700/STIM-class parts are
  0.05..0.15) and chosen so that the 0.5 °/h Allan floor stands out of the white noise:
  at the GM peak (τ = 189 s) the ARW contributes 0.05·60/√189 = 0.22 °/h, less than half
  of the floor, which makes the floor measurable in the Allan test (tests/python).
* In-run bias instability (not in Table 1): 1/10 of the turn-on bias for accelerometers
  (in-run drift is typically an order below run-to-run repeatability); for gyros 1/2 of
  it for the optical grades and tactical (a 1 °/h part has a ~0.5 °/h floor), 1/3 for
  mid-grade, 1/10 for automotive MEMS (20 °/h floor, typical of automotive yaw-rate
  sensors).
  GM correlation time 300 s for the navigation grades, 100 s for the MEMS grades
  (thermal time constants of MEMS packages are minutes).
* Scale factor / misalignment: typical calibrated values of each technology — RLG
  5..10 ppm, navigation quartz accelerometers 20..100 ppm, mechanical-axis residual
  misalignment 2..20 arcsec (0.01..0.1 mrad) for navigation grades; tactical MEMS
  300..500 ppm and 0.5 mrad; automotive MEMS 0.5..1 % and 5 mrad (~0.3°).
* g-sensitivity G_g only for the MEMS grades (optical gyros have none worth modelling):
  tactical MEMS 2 °/h/g (compensated; comparable to, not larger than, the 1 °/h Table 1
  bias, since a static IMU sees 1 g), automotive MEMS 0.05 °/s/g = 180 °/h/g (the order
  of consumer/automotive datasheets, again comparable to the 200 °/h bias). These are
  order-of-magnitude choices. Converted to rad/s per m/s²; a static IMU sees G_g·g as an
  extra constant bias, a turning/braking car a dynamic one.
* mid-grade (BINS-Tek-like, seed 000): the spec's free-inertial drift of 1.5..2 nmi/h is
  the "1 nmi/h class", whose gyros are ~0.01..0.02 °/h (the position error rate of a
  gyro bias ε is of order R·ε: 6.4e6 m × 0.015 °/h = 1.7 km/h ≈ 0.9 nmi/h, plus the
  alignment errors). The same bias sets the heading error: gyrocompassing leaves
  δH = ε_E / (Ω cos φ) = 0.015 / (15.04 · cos 56°) rad ≈ 0.10° (at φ = 56°, Ω = 15.04
  °/h), and the up gyro adds
  ε_U·t ≈ 0.015° per hour of free navigation, so after an hour the heading error is
  ~0.1..0.15° — the spec's 0.15°. Hence turn-on gyro bias 0.015 °/h (7.27e-8 rad/s), a
  0.005 °/h floor, FOG-class ARW 0.003 °/√h. Accelerometers: 1e-3 m/s² (100 µg) levels
  to 0.006°, well inside the spec's 0.04° pitch/roll error (which must also cover the
  dynamic errors).

Odometer
========
Four ABS wheel speeds (FL, FR, RL, RR; m/s, signed; DBC WheelSpeeds: 0.02 m/s, 50 Hz).
The truth's ``speed_mps`` is taken as the speed of the rear-axle midpoint along the body y
axis (the kinematic bicycle model's reference point: no lateral velocity there, so the
heading rate is curvature × speed). With r = heading rate (right turn positive, so the
body z rate is -r), track w, wheelbase L, a body point p = (x right, y forward) moves
with ``(r·p_y, s - r·p_x)``; for the wheel contact points::

    v_RL = s + r w/2,   v_RR = s - r w/2                      (right wheels inside a right turn)
    v_FL = sign(s + r w/2) · sqrt((s + r w/2)² + (r L)²)      (steered wheel rolls along its
    v_FR = sign(s - r w/2) · sqrt((s - r w/2)² + (r L)²)       velocity: exact Ackermann)

then scale error (1 + μ) (seed 000's μ, plus an optional per-wheel spread), optional
slip, latency (value at t = truth at t - latency), optional white noise, rounding to
the nearest 0.02 m/s and the DBC range; a sample whose delayed truth speed and yaw rate
are exactly zero is exactly 0 on all four wheels.

GNSS
====
Epochs at ``rate_hz`` (1..10 Hz) on the grid t = t0 + j/rate; an epoch reported at t
carries the truth at t - latency plus errors; epochs whose interval [t - latency, t]
touches an outage are not produced. Position error per E, N, U: white + first-order
Gauss-Markov (simulated on the full epoch grid, outages included, so an outage does not
change the other epochs' errors) + rare multipath outliers (probability per epoch, random
horizontal direction, magnitude uniform in [0.5, 1.5] × outlier_h_m). Velocity error:
white. Reported accuracies are consistent with the modelled (outlier-free) error:
``hacc_m`` = radius holding 68.27 % of the horizontal errors (circular Gaussian:
1.5152 σ per axis), ``vacc_m`` = σ_U, ``sacc_mps`` = 68.27 % radius of the horizontal
velocity error. Multipath outliers are not in hacc (receivers under-report them).
The first ``reacquire_s`` after an outage are produced with fix_type 0 and valid False.
Preset ``none`` (``enabled=False``): no receiver, no epoch at all.
Faults for the tests of the firmware's GNSS gate (100 m jumps, a frozen fix, a latency
spike): :func:`apply_gnss_faults`, from a scenario's ``[gnss_faults]``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tools import geodesy

G0_MPS2 = 9.80665                     # standard gravity: µg -> m/s²
DEG_PER_H_TO_RPS = math.pi / 180.0 / 3600.0
ARW_DEG_PER_RTH_TO_RAD_PER_RTS = math.pi / 180.0 / 60.0
P68 = math.erf(1.0 / math.sqrt(2.0))  # 0.682689: the 1-sigma probability
K68_2D = math.sqrt(-2.0 * math.log(1.0 - P68))  # 1.5152: Rayleigh radius holding P68


def gm_allan_variance(tau_s, corr_time_s, sigma):
    """Allan variance of a first-order Gauss-Markov process (std sigma, correlation time
    corr_time_s) at averaging time tau_s (IEEE Std 952 annex C; El-Sheimy et al. 2008)."""
    x = np.asarray(tau_s, dtype=float) / corr_time_s
    return (2.0 * sigma ** 2 / x) * (1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x))


def _gm_peak():
    x = np.linspace(1.0, 3.0, 200001)
    av = gm_allan_variance(x, 1.0, 1.0)
    i = int(np.argmax(av))
    return float(x[i]), float(np.sqrt(av[i]))


#: Allan maximum of a unit-std GM process: at tau = GM_ADEV_PEAK_TAU_PER_T * T it is
#: GM_ADEV_PEAK_FACTOR * sigma_GM (1.8926, 0.61736).
GM_ADEV_PEAK_TAU_PER_T, GM_ADEV_PEAK_FACTOR = _gm_peak()


def drive_seeds(seed: int) -> tuple:
    """The seeds of one drive's IMU, odometer and GNSS errors for tools.sim.run's --seed:
    one per model, distinct across seeds (3 seed, 3 seed + 1, 3 seed + 2)."""
    return 3 * seed, 3 * seed + 1, 3 * seed + 2


def _streams(seed, n):
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]


def _ar1(e, a, x_init):
    """x_k = a x_{k-1} + e_k along axis 0, with x_{-1} = x_init. Exact, vectorized by
    blocks of L samples with a^-L <= 1e3 (cumulative sums inside a block, a short loop
    carries the state from block to block)."""
    n = e.shape[0]
    if n == 0:
        return e.copy()
    if a <= 0.0:
        return e.copy()
    L = n if a >= 1.0 else int(max(1, min(n, math.floor(math.log(1e3) / -math.log(a)))))
    nb = -(-n // L)
    pad = nb * L - n
    rest = e.shape[1:]
    E = np.concatenate([e, np.zeros((pad,) + rest)]).reshape((nb, L) + rest)
    j = np.arange(1, L + 1, dtype=float).reshape((1, L) + (1,) * len(rest))
    apow = a ** j
    Y = np.cumsum(E / apow, axis=1) * apow          # zero-state response in each block
    aL = a ** L
    start = np.empty((nb,) + rest)
    s = np.asarray(x_init, dtype=float) * np.ones(rest)
    for b in range(nb):
        start[b] = s
        s = aL * s + Y[b, -1]
    X = Y + apow * start[:, None]
    return X.reshape((nb * L,) + rest)[:n]


def gauss_markov(rng, n, ncols, dt_s, corr_time_s, sigma):
    """n samples (n, ncols) of a stationary first-order Gauss-Markov process."""
    if sigma == 0.0 or n == 0:
        return np.zeros((n, ncols))
    a = math.exp(-dt_s / corr_time_s)
    x0 = sigma * rng.standard_normal(ncols)
    e = sigma * math.sqrt(1.0 - a * a) * rng.standard_normal((n, ncols))
    return _ar1(e, a, x0)


# ============================================================================ IMU
@dataclass(frozen=True)
class ImuSpec:
    """IMU error magnitudes, 1-sigma per axis (see the module docstring for the model)."""
    accel_bias_turnon_mps2: float = 0.0
    accel_bias_instability_mps2: float = 0.0      # Allan floor of the in-run GM part
    accel_bias_corr_time_s: float = 300.0
    accel_noise_ug_per_rthz: float = 0.0
    accel_scale_factor_ppm: float = 0.0
    accel_misalignment_mrad: float = 0.0
    gyro_bias_turnon_rps: float = 0.0
    gyro_bias_instability_rps: float = 0.0        # Allan floor of the in-run GM part
    gyro_bias_corr_time_s: float = 300.0
    gyro_arw_deg_per_rth: float = 0.0
    gyro_scale_factor_ppm: float = 0.0
    gyro_misalignment_mrad: float = 0.0
    gyro_g_sensitivity_rps_per_mps2: float = 0.0  # each element of G_g
    mounting_roll_deg: float = 0.0
    mounting_pitch_deg: float = 0.0
    mounting_yaw_deg: float = 0.0                 # clockwise, like the heading

    @property
    def accel_noise_mps2_per_rthz(self) -> float:
        return self.accel_noise_ug_per_rthz * 1e-6 * G0_MPS2

    @property
    def gyro_arw_rad_per_rts(self) -> float:
        return self.gyro_arw_deg_per_rth * ARW_DEG_PER_RTH_TO_RAD_PER_RTS

    @property
    def accel_gm_sigma_mps2(self) -> float:
        return self.accel_bias_instability_mps2 / GM_ADEV_PEAK_FACTOR

    @property
    def gyro_gm_sigma_rps(self) -> float:
        return self.gyro_bias_instability_rps / GM_ADEV_PEAK_FACTOR


def _dph(x):
    return x * DEG_PER_H_TO_RPS


PRESETS: dict[str, ImuSpec] = {
    "perfect": ImuSpec(),
    "marine": ImuSpec(
        accel_bias_turnon_mps2=1e-4, accel_bias_instability_mps2=1e-5,
        accel_bias_corr_time_s=300.0, accel_noise_ug_per_rthz=10.0,
        accel_scale_factor_ppm=20.0, accel_misalignment_mrad=0.01,
        gyro_bias_turnon_rps=5e-9, gyro_bias_instability_rps=_dph(0.0005),
        gyro_bias_corr_time_s=300.0, gyro_arw_deg_per_rth=0.001,
        gyro_scale_factor_ppm=5.0, gyro_misalignment_mrad=0.01),
    "aviation": ImuSpec(
        accel_bias_turnon_mps2=5e-4, accel_bias_instability_mps2=5e-5,
        accel_bias_corr_time_s=300.0, accel_noise_ug_per_rthz=20.0,
        accel_scale_factor_ppm=100.0, accel_misalignment_mrad=0.025,
        gyro_bias_turnon_rps=5e-8, gyro_bias_instability_rps=_dph(0.005),
        gyro_bias_corr_time_s=300.0, gyro_arw_deg_per_rth=0.002,
        gyro_scale_factor_ppm=10.0, gyro_misalignment_mrad=0.025),
    "intermediate": ImuSpec(
        accel_bias_turnon_mps2=3e-3, accel_bias_instability_mps2=3e-4,
        accel_bias_corr_time_s=300.0, accel_noise_ug_per_rthz=50.0,
        accel_scale_factor_ppm=300.0, accel_misalignment_mrad=0.1,
        gyro_bias_turnon_rps=5e-7, gyro_bias_instability_rps=_dph(0.05),
        gyro_bias_corr_time_s=300.0, gyro_arw_deg_per_rth=0.01,
        gyro_scale_factor_ppm=100.0, gyro_misalignment_mrad=0.1),
    "mid-grade": ImuSpec(
        accel_bias_turnon_mps2=1e-3, accel_bias_instability_mps2=1e-4,
        accel_bias_corr_time_s=300.0, accel_noise_ug_per_rthz=20.0,
        accel_scale_factor_ppm=100.0, accel_misalignment_mrad=0.05,
        gyro_bias_turnon_rps=_dph(0.015), gyro_bias_instability_rps=_dph(0.005),
        gyro_bias_corr_time_s=300.0, gyro_arw_deg_per_rth=0.003,
        gyro_scale_factor_ppm=50.0, gyro_misalignment_mrad=0.05),
    "tactical": ImuSpec(
        accel_bias_turnon_mps2=3e-2, accel_bias_instability_mps2=3e-3,
        accel_bias_corr_time_s=100.0, accel_noise_ug_per_rthz=300.0,
        accel_scale_factor_ppm=500.0, accel_misalignment_mrad=0.5,
        gyro_bias_turnon_rps=5e-6, gyro_bias_instability_rps=_dph(0.5),
        gyro_bias_corr_time_s=100.0, gyro_arw_deg_per_rth=0.05,
        gyro_scale_factor_ppm=300.0, gyro_misalignment_mrad=0.5,
        gyro_g_sensitivity_rps_per_mps2=_dph(2.0) / G0_MPS2),
    "automotive": ImuSpec(
        accel_bias_turnon_mps2=0.2, accel_bias_instability_mps2=2e-2,
        accel_bias_corr_time_s=100.0, accel_noise_ug_per_rthz=1500.0,
        accel_scale_factor_ppm=5000.0, accel_misalignment_mrad=5.0,
        gyro_bias_turnon_rps=1e-3, gyro_bias_instability_rps=_dph(20.0),
        gyro_bias_corr_time_s=100.0, gyro_arw_deg_per_rth=2.0,
        gyro_scale_factor_ppm=10000.0, gyro_misalignment_mrad=5.0,
        gyro_g_sensitivity_rps_per_mps2=_dph(180.0) / G0_MPS2),
}


@dataclass(frozen=True)
class ImuErrors:
    """One realisation of the IMU's constant errors (sensor frame)."""
    accel_bias_turnon_mps2: np.ndarray    # (3,)
    gyro_bias_turnon_rps: np.ndarray      # (3,)
    accel_M: np.ndarray                   # (3, 3) I + scale factors + misalignments
    gyro_M: np.ndarray                    # (3, 3)
    gyro_G_rps_per_mps2: np.ndarray       # (3, 3) g-sensitivity


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def mounting_C_sb(spec: ImuSpec) -> np.ndarray:
    """Body -> sensor rotation: C_sb = (Rz(-yaw) Rx(pitch) Ry(roll))^T."""
    C_bs = (_rz(-math.radians(spec.mounting_yaw_deg)) @ _rx(math.radians(spec.mounting_pitch_deg))
            @ _ry(math.radians(spec.mounting_roll_deg)))
    return C_bs.T


def _error_matrix(rng, sf_ppm, mis_mrad):
    d = np.zeros((3, 3))
    if sf_ppm:
        d += np.diag(sf_ppm * 1e-6 * rng.standard_normal(3))
    if mis_mrad:
        off = mis_mrad * 1e-3 * rng.standard_normal((3, 3))
        np.fill_diagonal(off, 0.0)
        d += off
    return np.eye(3) + d


def draw_imu_errors(spec: ImuSpec, seed: int) -> ImuErrors:
    """The constant errors apply_imu(truth, spec, seed) uses (same seed -> same values)."""
    r_ba, r_bg, r_ma, r_mg, r_g = _streams(seed, 9)[:5]
    return ImuErrors(
        accel_bias_turnon_mps2=spec.accel_bias_turnon_mps2 * r_ba.standard_normal(3),
        gyro_bias_turnon_rps=spec.gyro_bias_turnon_rps * r_bg.standard_normal(3),
        accel_M=_error_matrix(r_ma, spec.accel_scale_factor_ppm, spec.accel_misalignment_mrad),
        gyro_M=_error_matrix(r_mg, spec.gyro_scale_factor_ppm, spec.gyro_misalignment_mrad),
        gyro_G_rps_per_mps2=spec.gyro_g_sensitivity_rps_per_mps2 * r_g.standard_normal((3, 3)))


def apply_imu(truth, spec: ImuSpec, seed: int, *, errors: ImuErrors | None = None):
    """Sensor-frame increments (dtheta_rad, dv_mps), each (N+1, 3), row 0 zero.

    errors: the constant errors to use instead of draw_imu_errors(spec, seed) (tests,
    or a fixed calibration); the in-run bias and the noise still come from spec/seed."""
    dth_b = np.asarray(truth.dtheta_b_rad, dtype=float)
    dv_b = np.asarray(truth.dv_b_mps, dtype=float)
    t = np.asarray(truth.t_s, dtype=float)
    n = len(t) - 1
    if errors is None:
        errors = draw_imu_errors(spec, seed)
    r_gma, r_gmg, r_na, r_ng = _streams(seed, 9)[5:9]
    dth = dth_b.copy()
    dv = dv_b.copy()
    if spec.mounting_roll_deg or spec.mounting_pitch_deg or spec.mounting_yaw_deg:
        C = mounting_C_sb(spec)
        dth = dth @ C.T
        dv = dv @ C.T
    dv_s = dv.copy()                       # exact sensor-frame dv, for the g-sensitivity
    I3 = np.eye(3)
    if np.any(errors.accel_M != I3):
        dv = dv + dv_s @ (errors.accel_M - I3).T
    if np.any(errors.gyro_M != I3):
        dth = dth + dth @ (errors.gyro_M - I3).T
    if np.any(errors.gyro_G_rps_per_mps2 != 0.0):
        dth = dth + dv_s @ errors.gyro_G_rps_per_mps2.T
    if n > 0:
        dt = np.diff(t)[:, None]            # (n, 1) interval of rows 1..n
        dt_mean = float(t[-1] - t[0]) / n
        b_a = np.broadcast_to(errors.accel_bias_turnon_mps2, (n, 3))
        if spec.accel_bias_instability_mps2:
            b_a = b_a + gauss_markov(r_gma, n, 3, dt_mean, spec.accel_bias_corr_time_s,
                                     spec.accel_gm_sigma_mps2)
        if np.any(b_a != 0.0):
            dv[1:] += b_a * dt
        b_g = np.broadcast_to(errors.gyro_bias_turnon_rps, (n, 3))
        if spec.gyro_bias_instability_rps:
            b_g = b_g + gauss_markov(r_gmg, n, 3, dt_mean, spec.gyro_bias_corr_time_s,
                                     spec.gyro_gm_sigma_rps)
        if np.any(b_g != 0.0):
            dth[1:] += b_g * dt
        if spec.accel_noise_ug_per_rthz:
            dv[1:] += spec.accel_noise_mps2_per_rthz * np.sqrt(dt) * r_na.standard_normal((n, 3))
        if spec.gyro_arw_deg_per_rth:
            dth[1:] += spec.gyro_arw_rad_per_rts * np.sqrt(dt) * r_ng.standard_normal((n, 3))
    dth[0] = 0.0
    dv[0] = 0.0
    return dth, dv


def allan_deviation(rate_samples, dt, taus):
    """Overlapping Allan deviation of a rate signal sampled every dt (IEEE Std 952-1997
    annex C, overlapping estimator: sigma² = <(theta_{k+2m} - 2 theta_{k+m} + theta_k)²>
    / (2 tau²) over all k, theta the integrated rate). rate_samples (n,) or (n, k) (columns independent); each tau is
    rounded to m = round(tau/dt) samples; NaN where m < 1 or 2m > n."""
    y = np.asarray(rate_samples, dtype=float)
    one_d = y.ndim == 1
    if one_d:
        y = y[:, None]
    y = y - y.mean(axis=0)                 # Allan variance ignores an offset; keeps theta small
    n = y.shape[0]
    theta = np.concatenate([np.zeros((1, y.shape[1])), np.cumsum(y, axis=0) * dt])
    taus = np.atleast_1d(np.asarray(taus, dtype=float))
    out = np.full((len(taus), y.shape[1]), np.nan)
    for i, tau in enumerate(taus):
        m = int(round(tau / dt))
        if m < 1 or 2 * m > n:
            continue
        d = theta[2 * m:] - 2.0 * theta[m:-m] + theta[:-2 * m]
        out[i] = np.sqrt(np.mean(d * d, axis=0) / (2.0 * (m * dt) ** 2))
    return out[:, 0] if one_d else out


# ============================================================================ odometer
@dataclass(frozen=True)
class OdoSpec:
    rate_hz: float = 50.0
    mu: float = 0.012                    # scale error: reported = (1 + mu) x true (seed 000)
    wheel_mu_sigma: float = 0.0          # extra per-wheel scale error, 1-sigma (tyre spread)
    track_m: float = 1.6
    wheelbase_m: float = 2.7
    latency_s: float = 0.02
    quant_mps: float = 0.02              # DBC WheelSpeed* resolution
    range_mps: tuple = (-81.92, 81.9)    # DBC WheelSpeed* range
    noise_mps: float = 0.0               # white noise, 1-sigma, before rounding
    slip_frac: float = 0.0               # wheel-speed excess (driven wheels, accelerating)
    slip_accel_threshold_mps2: float = 2.5  # or deficit (all wheels, braking) beyond this
    driven_axle: str = "rear"            # "front", "rear" or "all"


def _ideal_wheels(s, r, track_m, wheelbase_m):
    half = 0.5 * track_m
    lon_l = s + r * half
    lon_r = s - r * half
    lat = r * wheelbase_m
    fl = np.sign(lon_l) * np.sqrt(lon_l * lon_l + lat * lat)
    fr = np.sign(lon_r) * np.sqrt(lon_r * lon_r + lat * lat)
    return np.column_stack([fl, fr, lon_l, lon_r])


def wheel_speeds(truth, spec: OdoSpec, seed: int):
    """(t_s (M,), speeds_mps (M, 4) FL FR RL RR) at spec.rate_hz; see the module doc."""
    t = np.asarray(truth.t_s, dtype=float)
    s_all = np.asarray(truth.speed_mps, dtype=float)
    r_all = np.asarray(truth.yaw_rate_rps, dtype=float)
    t0, t1 = float(t[0]), float(t[-1])
    m = int(math.floor((t1 - t0) * spec.rate_hz + 1e-9)) + 1
    tw = t0 + np.arange(m) / spec.rate_hz
    tm = tw - spec.latency_s
    s = np.interp(tm, t, s_all)
    r = np.interp(tm, t, r_all)
    v = _ideal_wheels(s, r, spec.track_m, spec.wheelbase_m)
    r_mu, r_noise = _streams(seed, 2)
    scale = 1.0 + spec.mu + (spec.wheel_mu_sigma * r_mu.standard_normal(4) if spec.wheel_mu_sigma
                             else np.zeros(4))
    v = v * scale
    if spec.slip_frac:
        acc = np.interp(tm, t, np.gradient(s_all, t)) * np.sign(s)
        driven = {"front": [0, 1], "rear": [2, 3], "all": [0, 1, 2, 3]}[spec.driven_axle]
        spin = acc > spec.slip_accel_threshold_mps2
        lock = acc < -spec.slip_accel_threshold_mps2
        v[np.ix_(spin, driven)] *= 1.0 + spec.slip_frac
        v[lock] *= 1.0 - spec.slip_frac
    if spec.noise_mps:
        v = v + spec.noise_mps * r_noise.standard_normal(v.shape)
    q = spec.quant_mps
    v = np.clip(np.round(v / q) * q, spec.range_mps[0], spec.range_mps[1])
    v[(s == 0.0) & (r == 0.0)] = 0.0
    return tw, v + 0.0                      # + 0.0: no negative zeros


# ============================================================================ GNSS
@dataclass(frozen=True)
class GnssSpec:
    """GNSS receiver errors, 1-sigma per axis (E, N: "h"; U: "v")."""
    rate_hz: float = 5.0
    latency_s: float = 0.0
    pos_white_h_m: float = 0.0
    pos_white_v_m: float = 0.0
    pos_gm_h_m: float = 0.0               # steady-state std of the correlated part
    pos_gm_v_m: float = 0.0
    pos_gm_corr_time_s: float = 120.0
    vel_white_h_mps: float = 0.0
    vel_white_v_mps: float = 0.0
    outlier_prob: float = 0.0             # per epoch
    outlier_h_m: float = 0.0              # mean horizontal magnitude (uniform 0.5..1.5 x)
    outlier_v_m: float = 0.0              # vertical: uniform in +-1.5 x this
    num_sats_mean: float = 9.0
    fix_type: int = 3                     # DBC FixType of a good epoch
    reacquire_s: float = 0.0              # no fix this long after an outage
    no_fix_acc_m: float = 99.9            # hacc/vacc reported without a fix
    enabled: bool = True                  # False: no receiver, no epoch at all

    @property
    def pos_sigma_h_m(self) -> float:
        """Per-axis std of the horizontal error without outliers."""
        return math.hypot(self.pos_white_h_m, self.pos_gm_h_m)

    @property
    def pos_sigma_v_m(self) -> float:
        return math.hypot(self.pos_white_v_m, self.pos_gm_v_m)

    @property
    def hacc_m(self) -> float:
        """Reported horizontal accuracy: radius holding 68.27 % of the errors."""
        return K68_2D * self.pos_sigma_h_m

    @property
    def vacc_m(self) -> float:
        return self.pos_sigma_v_m

    @property
    def sacc_mps(self) -> float:
        return K68_2D * self.vel_white_h_mps

    @property
    def horizontal_rms_m(self) -> float:
        """Design horizontal RMS error (DRMS), outliers included."""
        return math.sqrt(2.0 * self.pos_sigma_h_m ** 2
                         + self.outlier_prob * (13.0 / 12.0) * self.outlier_h_m ** 2)

    @property
    def horizontal_r95_m(self) -> float:
        """95 % horizontal radius of the Gaussian part (2.4477 sigma per axis)."""
        return math.sqrt(-2.0 * math.log(0.05)) * self.pos_sigma_h_m


GNSS_PRESETS: dict[str, GnssSpec] = {
    # Standalone code receiver: correlated (iono/tropo/orbit/clock residuals) 2.0 m per
    # axis = 2.83 m horizontal RMS, white (noise, fast multipath) 0.71 m per axis = 1.0 m
    # horizontal RMS; total 3.0 m DRMS, hacc 3.2 m; vertical 1.5x; Doppler velocity
    # 0.05 m/s; u-blox-like 0.1 s output latency; 1 epoch in 500 with a 10..30 m
    # multipath error (+1.5 % on the RMS, included in horizontal_rms_m).
    "standalone": GnssSpec(
        rate_hz=5.0, latency_s=0.1, pos_white_h_m=0.71, pos_white_v_m=1.2,
        pos_gm_h_m=2.0, pos_gm_v_m=3.0, pos_gm_corr_time_s=120.0,
        vel_white_h_mps=0.05, vel_white_v_mps=0.08, outlier_prob=0.002, outlier_h_m=20.0,
        outlier_v_m=20.0, num_sats_mean=9.0, fix_type=3, reacquire_s=2.0),
    # Differential (seed 001: "about 2 m with differential correction"). Read as the way
    # DGNSS accuracy is usually quoted, 95 % horizontal (~2DRMS): R95 = 2.4477 sigma per
    # axis = 2.0 m -> sigma = 0.82 m per axis: correlated 0.70 m (correction age, residual
    # tropo, station distance), tau 60 s; white 0.42 m. DRMS 1.15 m, hacc 1.24 m.
    "differential": GnssSpec(
        rate_hz=5.0, latency_s=0.1, pos_white_h_m=0.42, pos_white_v_m=0.6,
        pos_gm_h_m=0.70, pos_gm_v_m=1.1, pos_gm_corr_time_s=60.0,
        vel_white_h_mps=0.03, vel_white_v_mps=0.05, outlier_prob=0.001, outlier_h_m=5.0,
        outlier_v_m=5.0, num_sats_mean=10.0, fix_type=4, reacquire_s=2.0),
    # No error, no latency: positions are the truth at the epoch times.
    "perfect": GnssSpec(rate_hz=5.0, latency_s=0.0, num_sats_mean=12.0, fix_type=4),
    # No receiver (seed 000's drive: the start and one known point only): no GNSS frames.
    "none": GnssSpec(enabled=False),
}


def _radii(lat_rad, h_m):
    """Meridian and prime-vertical radii of curvature plus the height (m)."""
    r_m, r_n = geodesy.radii_m(lat_rad)
    return r_m + h_m, r_n + h_m


def gnss_epochs(truth, spec: GnssSpec, seed: int) -> dict:
    """GNSS epochs as a dict of arrays (one row per produced epoch):

    t_s (report time), t_meas_s (= t_s - latency, the truth instant), lat_rad, lon_rad,
    h_m, v_enu_mps (M, 3), hacc_m, vacc_m, sacc_mps, num_sats (int), fix_type (int),
    valid (bool), err_enu_m (M, 3) the position error put in, outlier (bool).
    A spec with enabled False gives every key with no rows."""
    if not spec.enabled:
        return {"t_s": np.zeros(0), "t_meas_s": np.zeros(0), "lat_rad": np.zeros(0),
                "lon_rad": np.zeros(0), "h_m": np.zeros(0), "v_enu_mps": np.zeros((0, 3)),
                "hacc_m": np.zeros(0), "vacc_m": np.zeros(0), "sacc_mps": np.zeros(0),
                "num_sats": np.zeros(0, dtype=int), "fix_type": np.zeros(0, dtype=int),
                "valid": np.zeros(0, dtype=bool), "err_enu_m": np.zeros((0, 3)),
                "outlier": np.zeros(0, dtype=bool)}
    if not (1.0 <= spec.rate_hz <= 10.0):
        raise ValueError(f"GNSS rate {spec.rate_hz} Hz outside 1..10 Hz")
    t = np.asarray(truth.t_s, dtype=float)
    t0, t1 = float(t[0]), float(t[-1])
    m = int(math.floor((t1 - t0) * spec.rate_hz + 1e-9)) + 1
    te = t0 + np.arange(m) / spec.rate_hz     # full grid (errors simulated on it)
    tm = te - spec.latency_s
    dt = 1.0 / spec.rate_hz
    r_w, r_gm, r_out, r_v, r_sat = _streams(seed, 5)

    err = np.zeros((m, 3))
    sig_w = np.array([spec.pos_white_h_m, spec.pos_white_h_m, spec.pos_white_v_m])
    if np.any(sig_w):
        err += sig_w * r_w.standard_normal((m, 3))
    if spec.pos_gm_h_m or spec.pos_gm_v_m:
        g = gauss_markov(r_gm, m, 3, dt, spec.pos_gm_corr_time_s, 1.0)
        err += g * np.array([spec.pos_gm_h_m, spec.pos_gm_h_m, spec.pos_gm_v_m])
    outlier = np.zeros(m, dtype=bool)
    if spec.outlier_prob:
        u = r_out.random((m, 4))
        outlier = u[:, 0] < spec.outlier_prob
        mag = spec.outlier_h_m * (0.5 + u[:, 1])
        az = 2.0 * math.pi * u[:, 2]
        vert = spec.outlier_v_m * 1.5 * (2.0 * u[:, 3] - 1.0)
        err[outlier] += np.column_stack([mag * np.sin(az), mag * np.cos(az), vert])[outlier]
    verr = np.zeros((m, 3))
    sig_v = np.array([spec.vel_white_h_mps, spec.vel_white_h_mps, spec.vel_white_v_mps])
    if np.any(sig_v):
        verr = sig_v * r_v.standard_normal((m, 3))
    sats = np.rint(spec.num_sats_mean + gauss_markov(r_sat, m, 1, dt, 300.0, 1.5)[:, 0])
    sats = np.clip(sats, 4, 24).astype(int)

    keep = tm >= t0 - 1e-12
    no_fix = np.zeros(m, dtype=bool)
    for (a, b, *_label) in truth.outages:
        keep &= ~((te >= a) & (tm <= b))           # [tm, te] touches [a, b]
        if spec.reacquire_s > 0.0:
            no_fix |= (tm > b) & (tm < b + spec.reacquire_s)
    idx = np.nonzero(keep)[0]
    te, tm, err, verr, outlier, sats, no_fix = (x[idx] for x in (te, tm, err, verr, outlier,
                                                                 sats, no_fix))

    lat_t = np.interp(tm, t, np.asarray(truth.lat_rad, dtype=float))
    lon_unw = np.unwrap(np.asarray(truth.lon_rad, dtype=float))
    lon_t = np.interp(tm, t, lon_unw)
    h_t = np.interp(tm, t, np.asarray(truth.h_m, dtype=float))
    venu = np.asarray(truth.v_enu_mps, dtype=float)
    v_t = np.column_stack([np.interp(tm, t, venu[:, i]) for i in range(3)])
    if np.any(err):
        rm, rn = _radii(lat_t, h_t)
        lat = lat_t + err[:, 1] / rm
        lon = lon_t + err[:, 0] / (rn * np.cos(lat_t))
        h = h_t + err[:, 2]
    else:
        lat, lon, h = lat_t, lon_t, h_t
    lon = (lon + math.pi) % (2.0 * math.pi) - math.pi if np.any(np.abs(lon) > math.pi) else lon
    v = v_t + verr if np.any(verr) else v_t
    k = len(idx)
    hacc = np.full(k, spec.hacc_m)
    vacc = np.full(k, spec.vacc_m)
    sacc = np.full(k, spec.sacc_mps)
    fix = np.full(k, int(spec.fix_type))
    fix[no_fix] = 0
    hacc[no_fix] = spec.no_fix_acc_m
    vacc[no_fix] = spec.no_fix_acc_m
    sacc[no_fix] = 1.5
    sats[no_fix] = np.minimum(sats[no_fix], 3)
    return {"t_s": te, "t_meas_s": tm, "lat_rad": lat, "lon_rad": lon, "h_m": h,
            "v_enu_mps": v, "hacc_m": hacc, "vacc_m": vacc, "sacc_mps": sacc,
            "num_sats": sats, "fix_type": fix, "valid": ~no_fix, "err_enu_m": err,
            "outlier": outlier}


# ============================================================================ GNSS faults
_EPOCH_KEYS_FROZEN = ("lat_rad", "lon_rad", "h_m", "v_enu_mps", "hacc_m", "vacc_m", "sacc_mps",
                      "num_sats", "fix_type", "valid")
FAULT_EPOCH_SEARCH_S = 1.0   # a jump or spike needs an epoch within this of its t_s


def _epoch_at_or_after(t_s, t: float, what: str) -> int:
    after = np.nonzero(t_s >= t - 1e-9)[0]
    if len(after) == 0 or t_s[after[0]] > t + FAULT_EPOCH_SEARCH_S:
        raise ValueError(f"[gnss_faults] {what} at {t:g} s: no GNSS epoch within "
                         f"{FAULT_EPOCH_SEARCH_S:g} s after it (an outage, or after the drive)")
    return int(after[0])


def apply_gnss_faults(epochs: dict, faults: dict) -> tuple[dict, list]:
    """Bad GNSS epochs for the gate tests (a scenario's [gnss_faults], validated by
    scenario.load_scenario): (a new epoch dict, one log entry per fault).

    freeze [t0, t1]: every epoch with t0 <= t_s < t1 repeats the position, velocity,
    height, accuracies, satellites, fix type and validity of the last epoch before t0; its
    t_s and t_meas_s (the frame time and TimeOfWeek) go on advancing, as from a receiver or
    gateway that re-sends a stale solution with fresh time tags (err_enu_m: NaN there, the
    error depends on the motion). jumps [t_s, metres, azimuth_deg, duration_s]: the first
    epoch at or after t_s and every epoch up to duration_s after it report their position
    moved by metres towards azimuth_deg (clockwise from north; on the local radii);
    velocity, height and accuracies unchanged, err_enu_m includes the jump.
    latency_spike [t_s, extra_s]: the first epoch at or after t_s gets t_s + extra_s as
    its frame time, t_meas_s (its TimeOfWeek) unchanged; the epochs are then in delivery
    order (stable sort by t_s), so the E2E epoch counter follows the order on the bus.
    Applied in that order (freeze, jumps, spikes). A jump or spike with no epoch within
    FAULT_EPOCH_SEARCH_S after its time, a freeze with no epoch in it or none before it:
    ValueError.

    Log entries: kind, the fault's parameters, epochs (number of epochs changed),
    epoch_t_s (their original times), t_start_s / t_end_s (first and last frame time of
    the fault on the bus: a spike's t_end_s is its late delivery)."""
    ep = {k: np.array(v, copy=True) for k, v in epochs.items()}
    t = ep["t_s"]
    log = []
    for f in faults.get("freeze", []):
        sel = np.nonzero((t >= f["t0_s"] - 1e-9) & (t < f["t1_s"] - 1e-9))[0]
        before = np.nonzero(t < f["t0_s"] - 1e-9)[0]
        if len(sel) == 0 or len(before) == 0:
            raise ValueError(f"[gnss_faults] freeze {f['t0_s']:g}-{f['t1_s']:g} s: "
                             + ("no GNSS epoch in it" if len(sel) == 0 else "no epoch before it"))
        src = int(before[-1])
        for k in _EPOCH_KEYS_FROZEN:
            if k in ep:
                ep[k][sel] = ep[k][src]
        if "err_enu_m" in ep:
            ep["err_enu_m"][sel] = np.nan
        log.append({"kind": "freeze", "t0_s": f["t0_s"], "t1_s": f["t1_s"], "epochs": len(sel),
                    "frozen_epoch_t_s": float(t[src]), "epoch_t_s": t[sel].tolist(),
                    "t_start_s": float(t[sel[0]]), "t_end_s": float(t[sel[-1]])})
    for f in faults.get("jumps", []):
        i = _epoch_at_or_after(t, f["t_s"], "jump")
        sel = np.nonzero((t >= t[i] - 1e-9) & (t <= t[i] + f["duration_s"] + 1e-9))[0]
        az = math.radians(f["azimuth_deg"])
        de, dn = f["metres"] * math.sin(az), f["metres"] * math.cos(az)
        rm, rn = _radii(ep["lat_rad"][sel], ep["h_m"][sel])
        lat = ep["lat_rad"][sel]
        ep["lat_rad"][sel] = lat + dn / rm
        ep["lon_rad"][sel] = ep["lon_rad"][sel] + de / (rn * np.cos(lat))
        if "err_enu_m" in ep:
            ep["err_enu_m"][sel, 0] += de
            ep["err_enu_m"][sel, 1] += dn
        log.append({"kind": "jump", "t_s": f["t_s"], "metres": f["metres"],
                    "azimuth_deg": f["azimuth_deg"], "duration_s": f["duration_s"],
                    "epochs": len(sel), "epoch_t_s": t[sel].tolist(),
                    "t_start_s": float(t[sel[0]]), "t_end_s": float(t[sel[-1]])})
    late = []
    for f in faults.get("latency_spike", []):
        i = _epoch_at_or_after(t, f["t_s"], "latency_spike")
        late.append((i, f["extra_s"]))
        log.append({"kind": "latency_spike", "t_s": f["t_s"], "extra_s": f["extra_s"],
                    "epochs": 1, "epoch_t_s": [float(t[i])],
                    "t_meas_s": float(ep["t_meas_s"][i]),
                    "t_start_s": float(t[i]), "t_end_s": float(t[i] + f["extra_s"])})
    if late:
        t_new = t.copy()
        for i, extra in late:
            t_new[i] += extra
        ep["t_s"] = t_new
        order = np.argsort(t_new, kind="stable")
        ep = {k: v[order] for k, v in ep.items()}
    return ep, log


__all__ = ["ImuSpec", "ImuErrors", "PRESETS", "draw_imu_errors", "apply_imu",
           "mounting_C_sb", "allan_deviation", "gm_allan_variance", "gauss_markov",
           "GM_ADEV_PEAK_FACTOR", "GM_ADEV_PEAK_TAU_PER_T", "OdoSpec", "wheel_speeds",
           "GnssSpec", "GNSS_PRESETS", "gnss_epochs", "apply_gnss_faults", "drive_seeds"]
