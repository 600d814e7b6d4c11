"""A GNSS receiver at the measurement level (issue #20; seed 001's test stand, which turns
the true trajectory into pseudoranges and pseudorange rates with orbit, clock and
atmospheric errors): what a tightly coupled filter reads, satellite by satellite.

    python -m tools.sim.receiver [--scenario default] [--canyon A-B:RATIO ...] [--seed 1]
                                 [--list T0 T1 [--every 15]]

prints, for the scenario's drive, the satellites in view and the least-squares solution of
the simulated measurements (tools/gnss_raw.solve) against the truth; with --list, each
epoch's satellites (PRN:elevation/azimuth, deg; the satellite position is that of the
transmit time, a few arcseconds off) from T0 to T1 s. The scenario's own [gnss_raw]
receiver is used unless --canyon is given; --seed N draws what tools.sim.run's seed N
draws.

The model, each part from the physics or a published figure (docs/simulator.md):
- constellation: a GPS-like Walker 24/6/1 (24 satellites, 6 planes 60 deg apart in right
  ascension, inclination 55 deg, circular orbits of semi-major axis 26,559.7 km, the
  planes' satellites 15 deg apart in argument of latitude from plane to plane); positions
  from Kepler's laws, rotated into ECEF; the satellite position carried is that of the
  transmit time, in the ECEF axes of that time (the protocol's convention);
- visibility: an elevation mask (10 deg), and urban canyons: streets along the car's heading
  with buildings of height H at W/2 to each side hide a satellite whose elevation is below
  atan(2H/W |sin(azimuth - heading)|) (canyon ratio 2H/W; 3 leaves 1 to 3 satellites);
- receiver clock: bias and drift as the two-state model of a TCXO with Allan variance
  coefficients h0 = 2e-19, h-2 = 2e-20 (Brown & Hwang, Introduction to Random Signals and
  Applied Kalman Filtering, table 9.1: S_b = h0/2 c^2, S_d = 2 pi^2 h-2 c^2), starting at
  +-1 ms and +-0.5 ppm; above 1 ms the receiver steps its clock back by 1 ms (ClockReset);
- atmosphere: the residuals after the receiver's models, zenith troposphere 0.1 m and
  ionosphere 1 m (a broadcast Klobuchar model removes about half of the delay), as first-
  order Gauss-Markov processes of 30 min, mapped by 1/sin(elevation) (the flat-Earth
  obliquity, bounded at 10 deg);
- multipath: a Gauss-Markov error per satellite (20 s) of 1-sigma 0.2 + 3 exp(-el/10 deg) m,
  its rate 0.02 m/s; code noise from C/N0 (a DLL of 1 chip spacing: 0.5 m at 45 dB-Hz,
  C/N0 = 30 + 20 sin(el) dB-Hz), Doppler noise 0.05 m/s at 45 dB-Hz, both scaling with
  10^((45 - C/N0)/20);
- orbit and satellite clock: broadcast residuals of 1 m along the line of sight (GM 1 h).
The receiver reports each pseudorange's sigma from its own noise, multipath and atmosphere
model (what a receiver's RAIM-grade sigma holds), and the range-rate sigma likewise.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from tools import geodesy
from tools import gnss_raw as gr
from tools.sim import sensors

# Walker 24/6/1, GPS-like (IS-GPS-200 nominal semi-major axis)
N_PLANES = 6
SATS_PER_PLANE = 4
INCLINATION_RAD = math.radians(55.0)
SEMI_MAJOR_M = 26559.7e3
GM_MPS = 3.986005e14                     # IS-GPS-200 mu
MEAN_MOTION_RPS = math.sqrt(GM_MPS / SEMI_MAJOR_M ** 3)
MULTIPATH_RATE_MPS = 0.02               # the multipath's rate error, 1 sigma


@dataclass
class ReceiverSpec:
    rate_hz: float = 1.0
    elevation_mask_deg: float = 10.0
    h0: float = 2e-19                    # TCXO white frequency noise
    h_2: float = 2e-20                   # TCXO random-walk frequency noise
    bias0_max_s: float = 1e-3
    drift0_max: float = 0.5e-6           # fractional frequency
    clock_step_s: float = 1e-3           # the receiver steps its clock back beyond this
    tropo_zenith_m: float = 0.1
    iono_zenith_m: float = 1.0
    atmo_corr_s: float = 1800.0
    orbit_clock_m: float = 1.0
    orbit_corr_s: float = 3600.0
    multipath_floor_m: float = 0.2
    multipath_low_m: float = 3.0
    multipath_el_scale_deg: float = 10.0
    multipath_corr_s: float = 20.0
    code_noise_m: float = 0.5            # at 45 dB-Hz
    doppler_noise_mps: float = 0.05      # at 45 dB-Hz
    canyons: list = field(default_factory=list)   # [(start_s, end_s, 2H/W[, max_sats])]
    # receiver faults, the test stand's (tests/python/test_gnss_tc.py): dicts of
    #   kind = "multipath": error_m added to the pseudorange of the satellite of elevation
    #          rank `rank` (0 the highest) from start_s to end_s (a reflection only);
    #   kind = "clock_step": the receiver's clock stepped by step_m at at_s, flagged in
    #          GNSS_RawEpoch ClockReset or not (`flagged`);
    #   kind = "no_rates": every range rate flagged invalid from start_s to end_s (a
    #          receiver that measures none)
    faults: list = field(default_factory=list)


_RAAN = np.repeat(np.radians(60.0 * np.arange(N_PLANES)), SATS_PER_PLANE)
_U0 = np.radians(90.0 * np.tile(np.arange(SATS_PER_PLANE), N_PLANES)
                 + 15.0 * np.repeat(np.arange(N_PLANES), SATS_PER_PLANE))
PRNS = np.arange(1, N_PLANES * SATS_PER_PLANE + 1)


def satellite_ecef(t_s):
    """Every satellite's ECEF position and velocity (arrays (24, 3), in the ECEF axes of its
    own time) at GPS time t_s: one time for all, or an array of 24, one per satellite."""
    t = np.broadcast_to(np.asarray(t_s, dtype=float), _RAAN.shape)
    u = _U0 + MEAN_MOTION_RPS * t
    cu, su = np.cos(u), np.sin(u)
    cr, sr = np.cos(_RAAN), np.sin(_RAAN)
    ci, si = math.cos(INCLINATION_RAD), math.sin(INCLINATION_RAD)
    r_i = SEMI_MAJOR_M * np.stack([cu * cr - su * ci * sr, cu * sr + su * ci * cr, su * si], 1)
    v_i = SEMI_MAJOR_M * MEAN_MOTION_RPS * np.stack(
        [-su * cr - cu * ci * sr, -su * sr + cu * ci * cr, cu * si], 1)
    th = geodesy.WGS84_OMEGA_IE_RPS * t
    ct, st = np.cos(th), np.sin(th)

    def rot(v):
        return np.stack([ct * v[:, 0] + st * v[:, 1], -st * v[:, 0] + ct * v[:, 1], v[:, 2]], 1)
    r_e = rot(r_i)
    w = geodesy.WGS84_OMEGA_IE_RPS
    v_e = rot(v_i) - np.stack([-w * r_e[:, 1], w * r_e[:, 0], np.zeros_like(t)], 1)
    return r_e, v_e, PRNS


def raw_seed(seed: int) -> int:
    """The receiver model's seed for tools.sim.run's --seed (the fixes' own, sensors.
    drive_seeds; the IMU and the wheels draw from others)."""
    return sensors.drive_seeds(seed)[2]


def dark_outages(truth, spec: ReceiverSpec) -> list:
    """[(start_s, end_s)] of the drive's outages with no raw epoch: a tunnel, not the
    outage of the fixes that a canyon of spec covers (there the receiver computes no fix
    from under four satellites, but tracks the ones along the street)."""
    return [(o0, o1) for (o0, o1, *_r) in truth.outages
            if not any(c[0] <= o0 and o1 <= c[1] for c in spec.canyons)]


# ReceiverSpec's figures that divide: never 0
POSITIVE_FIGURES = frozenset({"rate_hz", "atmo_corr_s", "orbit_corr_s", "multipath_corr_s",
                              "multipath_el_scale_deg", "clock_step_s"})


def spec_of(table: dict) -> ReceiverSpec:
    """The receiver of a scenario's [gnss_raw] table (tools/sim/scenario.py): its canyons
    and faults, and `receiver`, ReceiverSpec's figures other than the defaults (an unknown
    name, or canyons and faults given there, is refused: ValueError)."""
    over = table.get("receiver", {})
    if not isinstance(over, dict):
        raise ValueError("[gnss_raw] receiver must be a table of ReceiverSpec's figures")
    known = {f.name for f in dataclasses.fields(ReceiverSpec)} - {"canyons", "faults"}
    unknown = set(over) - known
    if unknown:
        raise ValueError(f"[gnss_raw] receiver: unknown figures {sorted(unknown)} "
                         f"(ReceiverSpec: {', '.join(sorted(known))})")
    for k, v in over.items():
        # every figure is a size (>= 0); a rate, a correlation time, a step or a scale
        # divides (> 0)
        positive = k in POSITIVE_FIGURES
        if (isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
                or v < 0.0 or (positive and v == 0.0)):
            raise ValueError(f"[gnss_raw] receiver: {k} = {v!r} is not a number "
                             f"{'> 0' if positive else '>= 0'}")
    over = {k: float(v) for k, v in over.items()}
    return ReceiverSpec(canyons=[tuple(c) for c in table.get("canyons", [])],
                        faults=list(table.get("faults", [])), **over)


def canyon_at(t_s: float, canyons) -> tuple:
    """(2H/W, the most satellites it leaves or 0 for no cap) of the canyon at t_s, or
    (0, 0). A canyon is (start_s, end_s, 2H/W[, max_sats]): max_sats keeps only that many of
    the highest satellites the mask leaves (a street whose far end is blocked too)."""
    for c in canyons:
        if c[0] <= t_s <= c[1]:
            return float(c[2]), int(c[3]) if len(c) > 3 else 0
    return 0.0, 0


def _gm_step(x, rng, dt, tau, sigma):
    a = math.exp(-dt / tau)
    return a * x + sigma * math.sqrt(1.0 - a * a) * rng.standard_normal(np.shape(x))


@dataclass
class RawTruth:
    """What went into one epoch: the true receiver state and each satellite's error."""
    t_s: float
    rx_m: np.ndarray
    v_rx_mps: np.ndarray
    clock_m: float
    drift_mps: float
    in_view: int


def simulate(truth, spec: ReceiverSpec, seed: int, t0_gps_s: float = 0.0,
             outages=None) -> list:
    """[(t_s, RawEpoch, RawTruth)] at spec.rate_hz over the truth's span (times in the
    truth's seconds; RawEpoch.tow_s is t0_gps_s + t). outages: [(a, b)] with no epoch
    (default: the truth's own GNSS outages)."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 20]))
    t = np.asarray(truth.t_s, dtype=float)
    dt = 1.0 / spec.rate_hz
    n = int(math.floor((t[-1] - t[0]) * spec.rate_hz + 1e-9)) + 1
    outages = [(a, b) for (a, b, *_r) in truth.outages] if outages is None else outages
    c = gr.C_MPS
    bias = spec.bias0_max_s * c * (2.0 * rng.random() - 1.0)
    drift = spec.drift0_max * c * (2.0 * rng.random() - 1.0)
    s_b = spec.h0 / 2.0 * c * c
    s_d = 2.0 * math.pi ** 2 * spec.h_2 * c * c
    nsat = N_PLANES * SATS_PER_PLANE
    tropo = spec.tropo_zenith_m * rng.standard_normal()
    iono = spec.iono_zenith_m * rng.standard_normal()
    orbit = spec.orbit_clock_m * rng.standard_normal(nsat)
    mp = rng.standard_normal(nsat)          # stationary from the start
    mp_rate = np.zeros(nsat)
    lon_unw = np.unwrap(np.asarray(truth.lon_rad, dtype=float))
    hdg_unw = np.unwrap(np.asarray(truth.heading_rad, dtype=float))
    venu = np.asarray(truth.v_enu_mps, dtype=float)
    out = []
    for k in range(n):
        te = float(t[0] + k * dt)
        # the clock (exact discretisation of the two-state model), the slow errors
        if k:
            qb = s_b * dt + s_d * dt ** 3 / 3.0
            qd = s_d * dt
            qbd = s_d * dt ** 2 / 2.0
            l11 = math.sqrt(qb)
            l21 = qbd / l11 if l11 > 0.0 else 0.0
            l22 = math.sqrt(max(qd - l21 * l21, 0.0))
            z1, z2 = rng.standard_normal(2)
            bias += drift * dt + l11 * z1
            drift += l21 * z1 + l22 * z2
            tropo = _gm_step(tropo, rng, dt, spec.atmo_corr_s, spec.tropo_zenith_m)
            iono = _gm_step(iono, rng, dt, spec.atmo_corr_s, spec.iono_zenith_m)
            orbit = _gm_step(orbit, rng, dt, spec.orbit_corr_s, spec.orbit_clock_m)
            a_mp = math.exp(-dt / spec.multipath_corr_s)
            mp = a_mp * mp + math.sqrt(1.0 - a_mp * a_mp) * rng.standard_normal(nsat)
            mp_rate = rng.standard_normal(nsat)
        clock_reset = False
        for f in spec.faults:
            if f["kind"] == "clock_step" and te - dt < f["at_s"] <= te:
                bias += f["step_m"]
                clock_reset = bool(f.get("flagged", False))
        if abs(bias) > spec.clock_step_s * c:
            bias -= math.copysign(spec.clock_step_s * c, bias)
            clock_reset = True
        noise_pr = rng.standard_normal(nsat)
        noise_rr = rng.standard_normal(nsat)
        if any(a <= te <= b for a, b in outages):
            continue
        lat = float(np.interp(te, t, truth.lat_rad))
        lon = float(np.interp(te, t, lon_unw))
        h = float(np.interp(te, t, truth.h_m))
        hdg = float(np.interp(te, t, hdg_unw))
        v_enu = np.array([np.interp(te, t, venu[:, i]) for i in range(3)])
        rx = gr.ecef_from_geodetic(lat, lon, h)
        enu = gr.enu_axes(lat, lon)
        v_rx = enu.T @ v_enu
        ratio, cap = canyon_at(te, spec.canyons)
        tow = t0_gps_s + te
        # every satellite at its transmit time (tau from the geometric range, iterated)
        p_all, _, _ = satellite_ecef(tow)
        tau = np.linalg.norm(p_all - rx, axis=1) / c
        for _ in range(3):
            p_all, v_all, prn = satellite_ecef(tow - tau)
            s_all = np.array([gr.rotate_z(p, geodesy.WGS84_OMEGA_IE_RPS * x)
                              for p, x in zip(p_all, tau)])
            tau = np.linalg.norm(s_all - rx, axis=1) / c
        p_all, v_all, prn = satellite_ecef(tow - tau)
        ep = gr.RawEpoch(tow_s=tow, clock_reset=clock_reset)
        in_view = 0
        for j in range(nsat):
            s_tx, v_tx = p_all[j], v_all[j]
            s_rx = gr.rotate_z(s_tx, geodesy.WGS84_OMEGA_IE_RPS * tau[j])
            v_srx = gr.rotate_z(v_tx, geodesy.WGS84_OMEGA_IE_RPS * tau[j])
            d = enu @ (s_rx - rx)
            el = math.atan2(d[2], math.hypot(d[0], d[1]))
            az = math.atan2(d[0], d[1])
            if el < math.radians(spec.elevation_mask_deg):
                continue
            if ratio > 0.0 and math.tan(el) < ratio * abs(math.sin(az - hdg)):
                continue
            in_view += 1
            rho = float(np.linalg.norm(s_rx - rx))
            e = (s_rx - rx) / rho
            obl = 1.0 / max(math.sin(el), math.sin(math.radians(10.0)))
            cn0 = 30.0 + 20.0 * math.sin(el)
            scale = 10.0 ** ((45.0 - cn0) / 20.0)
            s_mp = spec.multipath_floor_m + spec.multipath_low_m * math.exp(
                -math.degrees(el) / spec.multipath_el_scale_deg)
            s_code = spec.code_noise_m * scale
            s_dop = spec.doppler_noise_mps * scale
            err = (tropo + iono) * obl + orbit[j] + s_mp * mp[j] + s_code * noise_pr[j]
            rr_err = MULTIPATH_RATE_MPS * mp_rate[j] + s_dop * noise_rr[j]
            sig_pr = math.sqrt(s_code ** 2 + s_mp ** 2 + spec.orbit_clock_m ** 2 +
                               (spec.tropo_zenith_m ** 2 + spec.iono_zenith_m ** 2) * obl ** 2)
            sig_rr = math.hypot(s_dop, MULTIPATH_RATE_MPS)
            ep.meas.append(gr.RawMeas(
                sv_id=int(prn[j]), sat_pos_m=s_tx, sat_vel_mps=v_tx,
                pseudorange_m=rho + bias + err,
                range_rate_mps=float(e @ (v_srx - v_rx)) + drift + rr_err,
                pr_sigma_m=sig_pr, rr_sigma_mps=sig_rr, elevation_deg=math.degrees(el),
                cn0_dbhz=int(round(cn0))))
        ep.meas.sort(key=lambda m: -m.elevation_deg)
        ep.meas = ep.meas[:cap if cap > 0 else gr.MAX_SATS]
        for f in spec.faults:
            if not f["kind"] in ("multipath", "no_rates") or not (
                    f["start_s"] <= te <= f["end_s"]):
                continue
            if f["kind"] == "multipath" and f["rank"] < len(ep.meas):
                ep.meas[f["rank"]].pseudorange_m += f["error_m"]
            elif f["kind"] == "no_rates":
                for m in ep.meas:
                    m.rr_valid = False
        out.append((te, ep, RawTruth(t_s=te, rx_m=rx, v_rx_mps=v_rx, clock_m=bias,
                                     drift_mps=drift, in_view=in_view)))
    return out


def parse_canyon(text: str) -> tuple:
    span, _, rest = text.partition(":")
    a, _, b = span.partition("-")
    ratio, _, cap = rest.partition(":")
    return (float(a), float(b), float(ratio or 3.0)) + ((int(cap),) if cap else ())


def main(argv=None) -> int:
    from tools.sim import scenario as scen_mod, trajectory
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenario", default="default")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--canyon", action="append", default=[], type=parse_canyon,
                    help="START-END:RATIO[:MAX], a street canyon of 2H/W = RATIO leaving at most "
                         "MAX satellites (repeatable)")
    ap.add_argument("--imu-rate-hz", type=int, default=100,
                    help="the truth's sample rate (the receiver interpolates it; tools.sim.run's "
                         "default)")
    ap.add_argument("--list", type=float, nargs=2, default=None, metavar=("T0", "T1"),
                    help="print the satellites (PRN, elevation, azimuth in deg) of the epochs "
                         "from T0 to T1 s, every --every s")
    ap.add_argument("--every", type=float, default=15.0)
    a = ap.parse_args(argv)
    scen = scen_mod.load(a.scenario)
    truth = trajectory.generate(scen, a.imu_rate_hz)
    # the scenario's own receiver (its canyons, faults, figures) unless --canyon is given;
    # as tools.sim.run: no epoch in an outage a canyon does not cover
    own = scen.get("gnss_raw", {})
    spec = (spec_of(own) if own.get("enabled") and not a.canyon
            else ReceiverSpec(canyons=list(a.canyon)))
    # the drive's GPS time, outages and the receiver's seed as tools.sim.run makes them
    eps = simulate(truth, spec, raw_seed(a.seed), t0_gps_s=scen_mod.GPS_TOW0_S,
                   outages=dark_outages(truth, spec))
    if a.list:
        last = -math.inf
        for t, ep, tr in eps:
            if not a.list[0] <= t <= a.list[1] or t < last + a.every - 1e-9:
                continue
            last = t
            lat, lon, _ = gr.geodetic_from_ecef(tr.rx_m)
            enu = gr.enu_axes(lat, lon)
            sats = []
            for m in ep.meas:
                d = enu @ (np.asarray(m.sat_pos_m, dtype=float) - tr.rx_m)
                sats.append(f"{m.sv_id}:{m.elevation_deg:.0f}/"
                            f"{math.degrees(math.atan2(d[0], d[1])) % 360.0:.0f}")
            print(f"{t:7.1f} s  {len(ep.meas)} of {tr.in_view} in view  " + " ".join(sats))
    n_view = np.array([len(ep.meas) for _, ep, _ in eps])
    errs = []
    x0 = None
    for _, ep, tr in eps:
        s = gr.solve(ep.meas, x0)
        if s is None:
            continue
        x0 = s.pos_m
        lat, lon, _ = gr.geodetic_from_ecef(tr.rx_m)
        d = gr.enu_axes(lat, lon) @ (s.pos_m - tr.rx_m)
        errs.append(math.hypot(d[0], d[1]))
    errs = np.array(errs)
    print(f"{len(eps)} epochs; satellites in view: median {np.median(n_view):.0f}, "
          f"min {n_view.min()}, max {n_view.max()}; epochs with < 4: {(n_view < 4).sum()}")
    if errs.size:
        print(f"least squares vs truth, horizontal: rms {np.sqrt(np.mean(errs ** 2)):.2f} m, "
              f"median {np.median(errs):.2f} m, p95 {np.percentile(errs, 95):.2f} m "
              f"({errs.size} epochs)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
