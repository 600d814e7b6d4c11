"""Drive-simulator truth (tools/sim/trajectory.py): the Earth model (tools/geodesy.py)
against WGS-84 published values, exact increments at rest, self-consistency of increments
and truth through an independent strapdown mechanization, and the shipped scenarios."""

import math
from pathlib import Path

import numpy as np
import pytest

from tools import geodesy as geo
from tools.sim import trajectory as tr
from tools.sim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
SCEN = ROOT / "tools" / "sim" / "scenarios"


def scenario(segments, heading_deg=30.0, **vehicle):
    return {"name": "test", "start": {"lat_deg": 45.0, "lon_deg": 10.0, "h_m": 100.0,
                                      "heading_deg": heading_deg},
            "vehicle": vehicle, "segment": segments, "outage": []}


# --- Earth model --------------------------------------------------------------------------
def test_wgs84_published_values():
    # NIMA TR8350.2: b^2/a = R_M at the equator, polar radius of curvature c = a^2/b,
    # normal gravity at the equator and the poles (Table 3.4); radii at 45 deg as in
    # tests/test_earth.c
    cases = [(0.0, 6335439.3273, 6378137.0), (45.0, 6367381.8156, 6388838.2901),
             (90.0, 6399593.6258, 6399593.6258)]
    for lat_deg, rm_pub, rn_pub in cases:
        rm, rn = geo.earth_radii(math.sin(math.radians(lat_deg)))
        assert rm == pytest.approx(rm_pub, rel=1e-9)
        assert rn == pytest.approx(rn_pub, rel=1e-9)
        # the other rounding order of the same formula (the reports' and the GNSS model's)
        assert geo.radii_m(math.radians(lat_deg)) == pytest.approx((rm, rn), rel=1e-15)
    assert geo.gravity(0.0, 0.0) == pytest.approx(9.7803253359, rel=1e-9)
    assert geo.gravity(1.0, 0.0) == pytest.approx(9.8321849378, rel=1e-9)
    # free-air gradient ~ -3.086e-6 /s^2 at mid latitude
    grad = (geo.gravity(math.sin(math.radians(45.0)), 100.0)
            - geo.gravity(math.sin(math.radians(45.0)), 0.0)) / 100.0
    assert grad == pytest.approx(-3.086e-6, rel=2e-3)


def test_horizontal_distances_agree():
    """horizontal_error_m (rad, east and north parts) and horizontal_distance_m (deg) are
    the same distance, across the antimeridian too."""
    lat1, lon1 = np.radians([45.0, -33.9, 10.0]), np.radians([10.0, 151.2, 179.9999])
    lat2, lon2 = lat1 + np.array([1e-5, -2e-6, 0.0]), lon1 + np.array([-3e-6, 0.0, 4e-6])
    lon2 = (lon2 + math.pi) % (2.0 * math.pi) - math.pi
    d, de, dn = geo.horizontal_error_m(lat1, lon1, lat2, lon2)
    assert np.allclose(d, np.hypot(de, dn))
    assert de[2] > 0.0 and dn[0] > 0.0 > de[0]
    assert np.allclose(geo.horizontal_distance_m(*np.degrees([lat1, lon1, lat2, lon2])), d,
                       rtol=1e-9)
    rm, rn = geo.radii_m(lat1[0])
    assert d[0] == pytest.approx(math.hypot(1e-5 * rm, 3e-6 * rn * math.cos(lat1[0])), rel=1e-9)


def test_euler_conventions():
    # H = 90 deg points the forward axis east; positive pitch lifts it; positive roll puts
    # the right side down (docs/frames.md)
    C = tr.quat_to_dcm(tr.quat_from_euler(0.0, 0.0, math.pi / 2))
    assert C[:, 1] == pytest.approx([1.0, 0.0, 0.0], abs=1e-15)
    C = tr.quat_to_dcm(tr.quat_from_euler(0.0, 0.1, 0.0))
    assert C[2, 1] == pytest.approx(math.sin(0.1), abs=1e-15)
    C = tr.quat_to_dcm(tr.quat_from_euler(0.1, 0.0, 0.0))
    assert C[2, 0] == pytest.approx(-math.sin(0.1), abs=1e-15)


# --- exact increments ---------------------------------------------------------------------
def test_stationary_increments_exact():
    rate, dur = 100.0, 60.0
    t = tr.generate(scenario([{"kind": "stop", "duration_s": dur}]), rate)
    n = len(t.t_s) - 1
    assert n == 6000 and t.t_s[-1] == pytest.approx(dur)
    dt = 1.0 / rate
    lat = math.radians(45.0)
    C_bn = tr.quat_to_dcm(tr.quat_from_euler(0.0, 0.0, math.radians(30.0)))
    w_ie = np.array([0.0, geo.WGS84_OMEGA_IE_RPS * math.cos(lat),
                     geo.WGS84_OMEGA_IE_RPS * math.sin(lat)])
    g = geo.gravity(math.sin(lat), 100.0)
    assert np.all(t.dtheta_b_rad[0] == 0.0) and np.all(t.dv_b_mps[0] == 0.0)
    assert np.abs(t.dtheta_b_rad[1:].sum(axis=0) - C_bn.T @ w_ie * dt * n).max() < 1e-12
    assert np.abs(t.dv_b_mps[1:] - C_bn.T @ np.array([0.0, 0.0, g]) * dt).max() < 1e-12
    assert np.all(t.lat_rad == lat) and np.all(t.h_m == 100.0)
    assert np.all(t.speed_mps == 0.0) and np.all(t.roll_rad == 0.0) and np.all(t.pitch_rad == 0.0)
    assert t.heading_rad == pytest.approx(math.radians(30.0), abs=1e-15)


def test_analytic_derivatives_consistent():
    sc = scenario([{"kind": "stop", "duration_s": 2}, {"kind": "speed", "to_mps": 10,
                                                        "accel_mps2": 2},
                   {"kind": "turn", "radius_m": 30, "angle_deg": 90},
                   {"kind": "hill", "distance_m": 200, "rise_m": 5},
                   {"kind": "speed", "to_mps": -3, "accel_mps2": 1.5},
                   {"kind": "turn", "radius_m": 10, "angle_deg": -40},
                   {"kind": "speed", "to_mps": 0, "accel_mps2": 1}])
    traj = tr.Trajectory(sc)
    t = np.linspace(0.01, traj.duration_s + 1.0, 5001)
    e = 1e-5
    k, kp, km = traj.kinematics(t), traj.kinematics(t + e), traj.kinematics(t - e)

    def d(key):
        return (kp[key] - km[key]) / (2 * e)

    assert np.abs(d("v") - k["a"]).max() < 1e-7
    assert np.abs(d("H") - k["Hd"]).max() < 1e-8
    assert np.abs(d("roll") - k["roll_rate"]).max() < 1e-8
    assert np.abs(d("pitch") - k["pitch_rate"]).max() < 1e-8
    assert np.abs(d("dist") - np.abs(k["s"])).max() < 1e-6
    assert math.degrees(k["H"][-1] - k["H"][0]) == pytest.approx(50.0, abs=1e-9)
    assert k["gamma"].max() > 0.0 and k["s"].min() == pytest.approx(-3.0)


def test_turn_at_standstill_rejected():
    with pytest.raises(ValueError):
        tr.Trajectory(scenario([{"kind": "turn", "radius_m": 10, "angle_deg": 90}]))
    with pytest.raises(ValueError):
        tr.Trajectory(scenario([{"kind": "speed", "to_mps": 5, "accel_mps2": 1},
                                {"kind": "stop", "duration_s": 5}]))


# --- increments and truth agree: an independent strapdown mechanization ----------------------
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _qmul(a, b):
    return (a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0])


def _qrot(phi):
    n = math.sqrt(phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2)
    if n < 1e-300:
        return (1.0, 0.0, 0.0, 0.0)
    s = math.sin(0.5 * n) / n
    return (math.cos(0.5 * n), s * phi[0], s * phi[1], s * phi[2])


def _rotate(q, x):  # C_bn x
    w, a, b, c = q
    return ((w * w + a * a - b * b - c * c) * x[0] + 2 * (a * b - w * c) * x[1]
            + 2 * (a * c + w * b) * x[2],
            2 * (a * b + w * c) * x[0] + (w * w - a * a + b * b - c * c) * x[1]
            + 2 * (b * c - w * a) * x[2],
            2 * (a * c - w * b) * x[0] + 2 * (b * c + w * a) * x[1]
            + (w * w - a * a - b * b + c * c) * x[2])


def _earth(lat, h, v):
    sl, cl = math.sin(lat), math.cos(lat)
    w2 = 1.0 - geo.WGS84_E2 * sl * sl
    rn = geo.WGS84_A_M / math.sqrt(w2)
    rm = geo.WGS84_A_M * (1.0 - geo.WGS84_E2) / (w2 * math.sqrt(w2))
    U = geo.WGS84_OMEGA_IE_RPS
    w_ie = (0.0, U * cl, U * sl)
    w_en = (-v[1] / (rm + h), v[0] / (rn + h), v[0] * sl / cl / (rn + h))
    g = geo.gravity(sl, h)
    return rm, rn, w_ie, w_en, g


def strapdown(truth, n_steps):
    """Savage-style increment mechanization (docs/frames.md), plain double, independent of
    the generator: two-sample coning and sculling, rotation compensation, Earth and
    transport rate, Coriolis, gravity, trapezoidal position."""
    dt = 1.0 / truth.imu_rate_hz
    q = tuple(truth.q_bn[0])
    v = tuple(truth.v_enu_mps[0])
    v_prev = v
    lat, lon, h = truth.lat_rad[0], truth.lon_rad[0], truth.h_m[0]
    dth_prev = tuple(truth.dtheta_b_rad[1])
    dv_prev = tuple(truth.dv_b_mps[1])
    dth_all = truth.dtheta_b_rad.tolist()
    dv_all = truth.dv_b_mps.tolist()
    out = np.zeros((n_steps + 1, 3))
    out[0] = lat, lon, h
    for k in range(1, n_steps + 1):
        dth, dv = dth_all[k], dv_all[k]
        # velocity
        v_mid = tuple(v[i] + 0.5 * (v[i] - v_prev[i]) for i in range(3))
        rm, rn, w_ie, w_en, g = _earth(lat, h, v_mid)
        zeta = tuple((w_ie[i] + w_en[i]) * dt for i in range(3))
        r1 = _cross(dth, dv)
        r2 = _cross(dth_prev, dv)
        r3 = _cross(dv_prev, dth)
        dvb = tuple(dv[i] + 0.5 * r1[i] + (r2[i] + r3[i]) / 12.0 for i in range(3))
        dvn = _rotate(q, dvb)
        zc = _cross(zeta, dvn)
        cor = _cross(tuple(2.0 * w_ie[i] + w_en[i] for i in range(3)), v_mid)
        grav = (0.0, 0.0, -g)
        dvn = tuple(dvn[i] - 0.5 * zc[i] + (grav[i] - cor[i]) * dt for i in range(3))
        # position
        vbar = tuple(v[i] + 0.5 * dvn[i] for i in range(3))
        dlat = vbar[1] * dt / (rm + h)
        dlon = vbar[0] * dt / ((rn + h) * math.cos(lat + 0.5 * dlat))
        h_new = h + vbar[2] * dt
        lat += dlat
        lon += dlon
        h = h_new
        v_prev = v
        v = tuple(v[i] + dvn[i] for i in range(3))
        # attitude
        cc = _cross(dth_prev, dth)
        phi = tuple(dth[i] + cc[i] / 12.0 for i in range(3))
        _, _, w_ie2, w_en2, _ = _earth(lat, h, vbar)
        zeta2 = tuple(-(w_ie2[i] + w_en2[i]) * dt for i in range(3))
        q = _qmul(_qmul(_qrot(zeta2), q), _qrot(phi))
        nq = math.sqrt(sum(x * x for x in q))
        q = tuple(x / nq for x in q)
        dth_prev, dv_prev = dth, dv
        out[k] = lat, lon, h
    return out, np.array(q), np.array(v)


def test_increments_reproduce_truth_through_strapdown():
    segs = [{"kind": "stop", "duration_s": 5},
            {"kind": "speed", "to_mps": 10, "accel_mps2": 2},
            {"kind": "turn", "radius_m": 30, "angle_deg": 90},
            {"kind": "hill", "distance_m": 200, "grade_pct": 8},
            {"kind": "speed", "to_mps": 6, "accel_mps2": 1.5},
            {"kind": "turn", "radius_m": 15, "angle_deg": -120},
            {"kind": "speed", "to_mps": 14, "accel_mps2": 1.5},
            {"kind": "turn", "radius_m": 80, "angle_deg": 60},
            {"kind": "straight", "distance_m": 200},
            {"kind": "speed", "to_mps": 0, "accel_mps2": 2.5},
            {"kind": "speed", "to_mps": -2, "accel_mps2": 1},
            {"kind": "turn", "radius_m": 8, "angle_deg": 45},
            {"kind": "speed", "to_mps": 0, "accel_mps2": 1},
            {"kind": "stop", "duration_s": 60}]
    rate = 400.0
    truth = tr.generate(scenario(segs, roughness_deg=0.1), rate)
    n = int(120.0 * rate)
    assert len(truth.t_s) > n
    assert truth.dist_m[n] > 600.0 and truth.speed_mps[: n + 1].min() < -1.9
    assert np.abs(truth.grade_rad).max() > 0.07
    pos, q, v = strapdown(truth, n)
    rm, rn = geo.earth_radii(math.sin(truth.lat_rad[0]))
    dn = (pos[:, 0] - truth.lat_rad[: n + 1]) * (rm + 100.0)
    de = (pos[:, 1] - truth.lon_rad[: n + 1]) * (rn + 100.0) * math.cos(truth.lat_rad[0])
    dh = pos[:, 2] - truth.h_m[: n + 1]
    err = np.sqrt(dn ** 2 + de ** 2 + dh ** 2)
    assert err.max() < 1e-3, f"max position error {err.max():.6f} m"  # measured 6e-5 m
    assert np.abs(v - truth.v_enu_mps[n]).max() < 1e-5
    dq = tr.quat_mul(np.array([q[0], -q[1], -q[2], -q[3]]), truth.q_bn[n])
    att_err = 2.0 * math.atan2(np.linalg.norm(dq[1:]), abs(dq[0]))
    assert att_err < 1e-9


# --- shipped scenarios --------------------------------------------------------------------
@pytest.fixture(scope="module")
def default_truth():
    return tr.generate(load_scenario(SCEN / "default.toml"), 100.0)


def test_default_scenario(default_truth, tmp_path):
    t = default_truth
    n1 = len(t.t_s)
    assert 20 * 60 <= t.t_s[-1] <= 30 * 60
    assert t.t_s == pytest.approx(np.arange(n1) / 100.0)
    for name in ("t_s", "lat_rad", "lon_rad", "h_m", "roll_rad", "pitch_rad", "heading_rad",
                 "speed_mps", "yaw_rate_rps", "dist_m"):
        a = getattr(t, name)
        assert a.shape == (n1,), name
        assert np.all(np.isfinite(a)), name
    for name in ("v_enu_mps", "f_b_mps2", "w_ib_b_rps", "dtheta_b_rad", "dv_b_mps"):
        a = getattr(t, name)
        assert a.shape == (n1, 3), name
        assert np.all(np.isfinite(a)), name
    assert t.q_bn.shape == (n1, 4)
    assert np.abs(np.linalg.norm(t.q_bn, axis=1) - 1.0).max() < 1e-14
    assert np.all((t.heading_rad >= 0.0) & (t.heading_rad < 2.0 * math.pi))
    inside = [o for o in t.outages if 0.0 < o[0] < o[1] < t.t_s[-1]]
    assert len(inside) >= 2
    assert any(60 <= o[1] - o[0] <= 120 for o in inside)
    assert any(30 <= o[1] - o[0] <= 60 for o in inside)
    assert t.speed_mps.min() < 0.0 and t.speed_mps.max() > 15.0
    assert np.all(t.speed_mps[: 40 * 100 + 1] == 0.0)  # standing for the levelling
    assert np.all(np.diff(t.dist_m) >= 0.0)
    # path length agrees with the integral of |speed| (trapezoid at 100 Hz)
    assert t.dist_m[-1] == pytest.approx(np.trapezoid(np.abs(t.speed_mps), t.t_s), rel=1e-6)
    # the increments integrate the instantaneous rates
    assert np.abs(t.dtheta_b_rad[1:].sum(0) - np.trapezoid(t.w_ib_b_rps, t.t_s, axis=0)).max() < 1e-4
    # roll and pitch stay car-like
    assert np.abs(t.roll_rad).max() < math.radians(5.0)
    assert np.abs(t.pitch_rad).max() < math.radians(6.0)
    path = tmp_path / "truth.csv"
    t.to_csv(path)
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    assert header[0] == "t_s" and "heading_deg" in header and header[-1] == "speed_mps"
    data = np.loadtxt(path, delimiter=",", skiprows=1, max_rows=5)
    assert data.shape == (5, 12)


def test_figure8_returns_to_start():
    t = tr.generate(load_scenario(SCEN / "figure8.toml"), 50.0)
    assert 9 * 60 <= t.t_s[-1] <= 11 * 60
    rm, rn = geo.earth_radii(math.sin(t.lat_rad[0]))
    dn = (t.lat_rad[-1] - t.lat_rad[0]) * (rm + t.h_m[0])
    de = (t.lon_rad[-1] - t.lon_rad[0]) * (rn + t.h_m[0]) * math.cos(t.lat_rad[0])
    assert math.hypot(dn, de) < 5.0
    assert t.speed_mps[-1] == 0.0
    assert len(np.unique(np.round(t.speed_mps[np.abs(t.yaw_rate_rps) > 0.1], 6))) >= 4


def test_motorway_scenario():
    """The unseen route (issue #18's "other routes"): south and west of the equator and
    Greenwich all the way, 130 km/h through the whole 3-min tunnel, and the car standing
    at the service area for its 2 minutes inside the second outage, moving at both of its
    ends (GNSS lost before the stop, back after the car has left)."""
    t = tr.generate(load_scenario(SCEN / "motorway.toml"), 50.0)
    assert np.all(t.lat_rad < 0.0) and np.all(t.lon_rad < 0.0)
    assert t.speed_mps.max() == pytest.approx(36.0, abs=1e-9)
    (a1, b1, _), (a2, b2, _) = t.outages
    tunnel = (t.t_s >= a1) & (t.t_s <= b1)
    assert b1 - a1 == 180.0 and np.all(t.speed_mps[tunnel] == pytest.approx(36.0, abs=1e-9))
    inside = (t.t_s >= a2) & (t.t_s <= b2)
    assert np.count_nonzero(t.speed_mps[inside] == 0.0) / 50.0 >= 119.0
    assert t.speed_mps[t.t_s == a2][0] > 5.0 and t.speed_mps[t.t_s == b2][0] > 5.0
    climb = np.abs(np.diff(t.h_m)).sum()
    assert climb > 0.06 * 2500.0 / 2  # the 7 % hill: up and down, over half its length


def test_seed000_scenario():
    """Seed 000's drive: long enough for 20 minutes after the calibration at 3431 s,
    moving there, standing still for the levelling and at stops along the way."""
    sc = load_scenario(SCEN / "seed000.toml")
    traj = tr.Trajectory(sc)
    cal = sc["calibration"]
    assert cal["at_s"] == 3431.0 and cal["source"] in ("known_position", "gnss")
    assert traj.duration_s >= cal["at_s"] + 20 * 60
    assert sc["sim"] == {"imu": "mid-grade", "gnss": "none"}
    assert sc["odometer"]["mu"] == 0.012
    ini, mnt = sc["initialization"], sc["imu_mounting"]
    assert ini["heading_reference"] == "imu"
    assert mnt["yaw_deg"] + ini["heading_error_deg"] == pytest.approx(-0.177, abs=1e-12)
    # the commanded heading (start + yaw + error) falls on the DBC's 0.01 deg grid
    cmd = sc["start"]["heading_deg"] + mnt["yaw_deg"] + ini["heading_error_deg"]
    assert cmd * 100 == pytest.approx(round(cmd * 100), abs=1e-6)
    t = np.arange(0.0, traj.duration_s, 0.1)
    k = traj.kinematics(t)
    s = k["s"]
    assert np.all(s[t <= 40.0] == 0.0)
    assert abs(traj.kinematics(np.array([cal["at_s"]]))["s"][0]) > 10.0
    stops = [(a, b) for a, b, kind in traj.segment_times if kind == "stop"]
    assert len(stops) >= 12 and all(b - a >= 20.0 for a, b in stops)
    assert len([a for a, b in stops if a > cal["at_s"]]) >= 3
    assert 15.0 < s.max() < 32.0 and np.all(s >= 0.0)
    assert k["dist"][-1] > 50e3
