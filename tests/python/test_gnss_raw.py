"""Raw GNSS measurements through the protocol (issue #20): tools/gnss_raw.py's frames and
geometry, the Kingston receiver's gnss_raw.csv as raw epochs (tools/kingston/raw.py), and
the simulator's receiver model (tools/sim/receiver.py), each checked by an independent
least-squares solution against the truth."""
import math

import numpy as np
import pytest

from tools import gnss_raw as gr
from tools import navecu_can as nc
from tools.geodesy import WGS84_OMEGA_IE_RPS
from tools.kingston import convert
from tools.kingston import raw as kraw
from tools.sim import receiver, scenario, trajectory

# half an LSB of each signal (the DBC's scales)
HALF_LSB = {"pos": 0.01, "vel": 0.0625, "pr": 0.01, "rr": 0.005}


def horizontal_m(est, true):
    lat, lon, _ = gr.geodetic_from_ecef(true)
    d = gr.enu_axes(lat, lon) @ (np.asarray(est) - true)
    return math.hypot(d[0], d[1])


@pytest.fixture(scope="module")
def kingston():
    d = convert.load()
    eps = kraw.epochs(kraw.read(d.data_dir), d.gnss, convert.GNSS_HEIGHT_ABOVE_REF_M)
    return d, [(t, ep) for t, ep in eps if t < d.t0_gps + 600.0]


def roundtrip(epochs):
    sender = nc.E2ESender()
    frames = []
    for i, (t, ep) in enumerate(epochs):
        frames += gr.encode_epoch(sender, ep, i % 15, t)
    return frames, gr.decode_epochs(frames)


def test_frames_carry_every_value_to_half_an_lsb(kingston):
    _, eps = kingston
    frames, dec = roundtrip(eps)
    assert len(dec) == len(eps)
    n_sat = sum(len(ep.meas) for _, ep in eps)
    assert len(frames) == 5 * n_sat + len(eps)
    for (t, ep), de in zip(eps, dec):
        assert de.tow_s == pytest.approx(t, abs=5e-4)
        assert [m.sv_id for m in de.meas] == [m.sv_id for m in ep.meas]
        for a, b in zip(ep.meas, de.meas):
            assert np.all(np.abs(np.subtract(a.sat_pos_m, b.sat_pos_m)) <= HALF_LSB["pos"] + 1e-6)
            assert np.all(np.abs(np.subtract(a.sat_vel_mps, b.sat_vel_mps))
                          <= HALF_LSB["vel"] + 1e-6)
            assert abs(a.pseudorange_m - b.pseudorange_m) <= HALF_LSB["pr"] + 1e-6
            assert abs(a.range_rate_mps - b.range_rate_mps) <= HALF_LSB["rr"] + 1e-6
            assert b.pr_valid and b.rr_valid


def test_a_frame_lost_drops_its_satellite_only(kingston):
    _, eps = kingston
    frames, _ = roundtrip(eps[:3])
    # the first epoch's second satellite loses its GNSS_RawRate (frame 5 * 1 + 4)
    dec = gr.decode_epochs(frames[:9] + frames[10:])
    assert len(dec[0].meas) == len(eps[0][1].meas) - 1
    assert len(dec[1].meas) == len(eps[1][1].meas)


def test_kingston_raw_epochs_solve_to_the_reference(kingston):
    """The receiver's own fixes are 0.99 m (median) from the reference (the data README);
    the same receiver's corrected pseudoranges, decoded from the frames, solved by least
    squares, must be of that size: the conventions (corrections' signs, satellite axes at
    the transmit time, Doppler's sign) are right. A wrong one costs metres (the module's
    docstring: 1.5 to 11 m)."""
    d, eps = kingston
    _, dec = roundtrip(eps)
    ref = d.ref
    errs, vel_errs, res = [], [], []
    x0 = None
    for (t, _), ep in zip(eps, dec):
        s = gr.solve(ep.meas, x0)
        j = int(np.argmin(np.abs(ref["time_s"] - t)))
        if s is None or abs(ref["time_s"][j] - t) > 0.01:
            continue
        x0 = s.pos_m
        r = gr.ecef_from_geodetic(math.radians(ref["lat_deg"][j]),
                                  math.radians(ref["lon_deg"][j]), float(ref["height_m"][j]))
        errs.append(horizontal_m(s.pos_m, r))
        res.extend(np.abs(s.residuals_m))
        if s.vel_mps is not None:
            lat, lon, _ = gr.geodetic_from_ecef(r)
            e = gr.enu_axes(lat, lon)
            v_ref = e.T @ np.array([ref["ve_mps"][j], ref["vn_mps"][j], ref["vu_mps"][j]])
            vel_errs.append(float(np.linalg.norm((e @ (s.vel_mps - v_ref))[:2])))
    print(f"Kingston raw, first 600 s: {len(errs)} epochs, horizontal median "
          f"{np.median(errs):.2f} m, pseudorange residual median {np.median(res):.2f} m, "
          f"velocity median {np.median(vel_errs):.3f} m/s")
    assert len(errs) > 500
    assert np.median(errs) < 2.0 * 0.99
    assert np.median(res) < 1.0
    # the reference's velocity against the Doppler solution: a wrong sign is metres/s
    assert np.median(vel_errs) < 0.2


def test_kingston_satellite_velocities_are_the_positions_rate(kingston):
    """The satellites as sent: at the transmit time t - tau(t) each position changes at its
    velocity times (1 - dtau/dt), both in the axes of the transmit time. gnss_raw.csv's
    positions are in the receive time's axes and its velocities are not (tools/kingston/
    raw.py's docstring): turning the velocities back as the positions are misses by
    omega tau |v|, up to 16 mm/s in x and y, and the standstill's Doppler velocity was
    5 mm/s south. The CSV's positions print 0.1 mm, so a central difference over 2 s is
    good to about 0.1 mm/s: 1 mm/s is the bound."""
    d, eps = kingston
    tracks = {}
    for t, ep in eps:
        rx = kraw.receiver_at(d.gnss, t, convert.GNSS_HEIGHT_ABOVE_REF_M)
        for m in ep.meas:
            _, _, tau = gr.sat_in_receive_axes(m.sat_pos_m, m.sat_vel_mps, rx)
            tracks.setdefault(m.sv_id, []).append((t, m.sat_pos_m, m.sat_vel_mps, tau))
    worst, n = 0.0, 0
    for rows in tracks.values():
        t = np.array([r[0] for r in rows])
        pos = np.array([r[1] for r in rows])
        vel = np.array([r[2] for r in rows])
        tau = np.array([r[3] for r in rows])
        one = np.diff(t) == 1.0
        k = np.where(one[:-1] & one[1:])[0] + 1
        rate = (pos[k + 1] - pos[k - 1]) / 2.0
        tau_dot = (tau[k + 1] - tau[k - 1]) / 2.0
        err = rate - vel[k] * (1.0 - tau_dot)[:, None]
        if k.size:
            worst = max(worst, float(np.max(np.abs(err))))
            n += k.size
    print(f"Kingston satellites' velocities against their positions' rate: {n} epochs, "
          f"worst {1000.0 * worst:.3f} mm/s")
    assert n > 3000
    assert worst < 1e-3


def quiet_spec(**kw):
    """The receiver model with every error off (noise, clock noise, atmosphere, orbit,
    multipath): what is left is geometry."""
    base = dict(h0=0.0, h_2=0.0, tropo_zenith_m=0.0, iono_zenith_m=0.0, orbit_clock_m=0.0,
                multipath_floor_m=0.0, multipath_low_m=0.0, code_noise_m=0.0,
                doppler_noise_mps=0.0)
    base.update(kw)
    return receiver.ReceiverSpec(**base)


@pytest.fixture(scope="module")
def drive():
    return trajectory.generate(scenario.load("regress"), 10)


def test_simulated_geometry_solves_exactly(drive, monkeypatch):
    """Without errors the receiver model's pseudoranges and rates are the geometry and the
    clock: least squares recovers position, clock bias, velocity and drift (to 1 mm and
    1 mm/s; MULTIPATH_RATE_MPS switched off too), and through the frames to the protocol's
    resolution: 0.02 m in every coordinate (sigma 6 mm each, a few DOP: within 0.1 m), the
    satellites' velocities at 0.125 m/s (sigma 0.036 m/s on each line of sight, a 3-D
    velocity of a few DOP times that: within 0.3 m/s)."""
    monkeypatch.setattr(receiver, "MULTIPATH_RATE_MPS", 0.0)
    eps = receiver.simulate(drive, quiet_spec(), seed=3)[:60]
    assert all(len(ep.meas) >= 5 for _, ep, _ in eps)
    for _, ep, tr in eps:
        s = gr.solve(ep.meas)
        assert np.linalg.norm(s.pos_m - tr.rx_m) < 1e-3
        assert s.clock_m == pytest.approx(tr.clock_m, abs=1e-3)
        assert np.linalg.norm(s.vel_mps - tr.v_rx_mps) < 1e-3
        assert s.drift_mps == pytest.approx(tr.drift_mps, abs=1e-3)
    _, dec = roundtrip([(t, ep) for t, ep, _ in eps])
    for de, (_, _, tr) in zip(dec, eps):
        s = gr.solve(de.meas)
        assert np.linalg.norm(s.pos_m - tr.rx_m) < 0.1
        assert np.linalg.norm(s.vel_mps - tr.v_rx_mps) < 0.3


def test_errors_are_the_size_declared(drive):
    """The receiver's declared pseudorange sigma holds its errors: with the slow errors that
    are one draw per run switched off (atmosphere, orbit), the code noise and multipath
    against the geometry (the clock bias known) are within 1 sigma in 68 % of cases over 8
    receivers' first 120 s (about 340 independent multipath draws of 20 s: a binomial
    spread of 2.5 %, so 62..74 %). With every error on, the least-squares fix is metres."""
    inside, total = 0, 0
    for seed in range(1, 9):
        spec = receiver.ReceiverSpec(tropo_zenith_m=0.0, iono_zenith_m=0.0, orbit_clock_m=0.0)
        for t, ep, tr in receiver.simulate(drive, spec, seed=seed):
            if t > 120.0:
                break
            for m in ep.meas:
                s_rx, _, _ = gr.sat_in_receive_axes(m.sat_pos_m, m.sat_vel_mps, tr.rx_m)
                e = m.pseudorange_m - float(np.linalg.norm(s_rx - tr.rx_m)) - tr.clock_m
                inside += abs(e) <= m.pr_sigma_m
                total += 1
    errs = [horizontal_m(gr.solve(ep.meas).pos_m, tr.rx_m)
            for _, ep, tr in receiver.simulate(drive, receiver.ReceiverSpec(), seed=1)]
    print(f"simulated code and multipath within 1 sigma: {inside / total:.1%} of {total}; "
          f"least squares with every error median {np.median(errs):.2f} m")
    assert 0.62 <= inside / total <= 0.74
    assert np.median(errs) < 5.0


def test_a_street_canyon_leaves_one_to_three_satellites(drive):
    """Buildings twice as high as the street is wide on each side (2H/W = 4) hide every
    satellite below atan(4 |sin(azimuth - heading)|): 1 to 3 left, the rest of the drive
    with the open-sky 5 or more."""
    t_end = float(drive.t_s[-1])
    spec = receiver.ReceiverSpec(canyons=[(60.0, 120.0, 4.0)])
    eps = receiver.simulate(drive, spec, seed=1)
    inside = [len(ep.meas) for t, ep, _ in eps if 60.0 <= t <= 120.0]
    outside = [len(ep.meas) for t, ep, _ in eps if not 60.0 <= t <= 120.0]
    assert inside and outside and t_end > 120.0
    assert 0 <= min(inside) and max(inside) <= 3 and np.median(inside) >= 1
    assert min(outside) >= 5
    # a cap keeps the highest of them (issue #20's 2-satellite canyon, canyon5-raw.toml)
    capped = receiver.simulate(drive, receiver.ReceiverSpec(canyons=[(60.0, 120.0, 4.0, 2)]),
                               seed=1)
    for (t, ep, _), (_, ep_all, _) in zip(capped, eps):
        if 60.0 <= t <= 120.0:
            assert len(ep.meas) == min(2, len(ep_all.meas))
            assert all(m.elevation_deg >= n.elevation_deg for m in ep.meas
                       for n in ep_all.meas[len(ep.meas):])


def test_the_receiver_steps_its_clock(drive):
    """A receiver keeping its clock within 50 us (a step of 50 us): ClockReset on the epoch
    of the step, and the solved clock bias jumps by the step (15 km) there, by the drift
    between other epochs."""
    spec = quiet_spec(clock_step_s=50e-6, bias0_max_s=45e-6, drift0_max=5e-6)
    eps = receiver.simulate(drive, spec, seed=2)
    resets = [k for k, (_, ep, _) in enumerate(eps) if ep.clock_reset]
    assert resets
    k = resets[0]
    assert k > 0
    b = [gr.solve(eps[i][1].meas).clock_m for i in (k - 1, k)]
    step = 50e-6 * gr.C_MPS
    drift = eps[k][2].drift_mps
    dt = eps[k][0] - eps[k - 1][0]
    assert abs(abs(b[1] - b[0] - drift * dt) - step) < 1e-3


def test_float32_cannot_form_the_receiver_ecef():
    """Why the firmware's GNSS geometry is fixed point (firmware/nav/gnss_geom.c,
    docs/numeric-design.md): the receiver's ECEF position from float32 latitude, longitude,
    sin and cos is off by decimetres to metres, against a need of millimetres."""
    rng = np.random.default_rng(1)
    f = np.float32
    worst = 0.0
    for _ in range(20000):
        lat, lon, h = rng.uniform(-1.5, 1.5), rng.uniform(-3.1, 3.1), rng.uniform(-500, 9000)
        ref = gr.ecef_from_geodetic(lat, lon, h)
        la, lo = f(lat), f(lon)
        n = f(gr.WGS84_A_M) / np.sqrt(f(1) - f(gr.WGS84_E2) * np.sin(la) * np.sin(la))
        x = np.array([(n + f(h)) * np.cos(la) * np.cos(lo), (n + f(h)) * np.cos(la) * np.sin(lo),
                      (n * (f(1) - f(gr.WGS84_E2)) + f(h)) * np.sin(la)], dtype=np.float32)
        worst = max(worst, float(np.max(np.abs(x.astype(float) - ref))))
    print(f"float32 ECEF of the receiver: worst error {worst:.2f} m over 20,000 positions")
    assert worst > 0.1


def test_docs_test_vector_is_what_the_encoder_sends():
    """docs/can.md's raw GNSS test vector (a third party's check of its encoder) is what
    tools/gnss_raw.encode_epoch sends for the values the document lists."""
    import re
    from pathlib import Path
    doc = (Path(__file__).resolve().parents[2] / "docs" / "can.md").read_text()
    rows = dict(re.findall(r"^\| (GNSS_Raw\w+) \| 0x13[1-6] \| `([0-9A-F ]+)` \|$", doc, re.M))
    assert len(rows) == 6, rows
    m = gr.RawMeas(sv_id=12, sat_pos_m=[15600000.12, 7540000.50, 20140000.04],
                   sat_vel_mps=[-1850.0, 2290.0, 1125.0], pseudorange_m=21345678.90,
                   range_rate_mps=-345.67, pr_sigma_m=3.2, rr_sigma_mps=0.05,
                   elevation_deg=47.0, cn0_dbhz=44)
    ep = gr.RawEpoch(tow_s=302400.5, clock_reset=False)
    ep.meas = [m]
    db = nc.load_db()
    for msg in gr.encode_epoch(nc.E2ESender(db), ep, 3, 0.0):
        name = db.get_message_by_frame_id(msg.arbitration_id).name
        assert msg.data.hex(" ").upper() == rows[name], name


def test_a_scenario_sets_the_receivers_figures():
    """[gnss_raw] receiver = {...} sets ReceiverSpec's figures (tools/sim/scenario.py): a
    scenario based on canyon5-raw keeps its canyon (the table merged key by key) and has
    the errors it switches off at zero, the others at their defaults; an unknown figure,
    or the canyons given there, is refused."""
    base = receiver.spec_of(scenario.load("canyon5-raw")["gnss_raw"])
    exact = receiver.spec_of(scenario.load("canyon5-raw-exact")["gnss_raw"])
    assert exact.canyons == base.canyons == [(800, 1100, 4.0, 2)]
    assert base.orbit_clock_m > 0.0 and base.code_noise_m > 0.0
    for f in ("tropo_zenith_m", "iono_zenith_m", "orbit_clock_m", "multipath_floor_m",
              "multipath_low_m", "code_noise_m", "doppler_noise_mps"):
        assert getattr(exact, f) == 0.0
    assert (exact.h0, exact.h_2) == (base.h0, base.h_2)   # the clock as it is
    for bad in ({"orbit_m": 0.0}, {"canyons": []}):
        with pytest.raises(ValueError):
            receiver.spec_of({"enabled": True, "receiver": bad})


def test_a_scenario_receivers_figures_are_checked():
    """The receiver's figures must be numbers, not negative, and the ones that divide
    (rates, correlation times) positive: refused with the figure named."""
    for bad in ({"orbit_clock_m": -1.0}, {"orbit_clock_m": "1"}, {"multipath_corr_s": 0.0},
                {"code_noise_m": True}, {"code_noise_m": float("nan")}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            receiver.spec_of({"enabled": True, "receiver": bad})
    with pytest.raises(ValueError):
        receiver.spec_of({"enabled": True, "receiver": 5})
    assert receiver.spec_of({"receiver": {"orbit_clock_m": 0}}).orbit_clock_m == 0.0
    # and when the scenario is read
    import tempfile
    from pathlib import Path
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "bad.toml"
        f.write_text(f'base = "{scenario.scenario_path("canyon5-raw")}"\n'
                     '[gnss_raw]\nreceiver = {orbit_clock_m = -1.0}\n')
        with pytest.raises(ValueError, match="orbit_clock_m"):
            scenario.load_scenario(f)


def _five_satellites():
    """A receiver at Kingston (44.23 N, 76.5 W, 40 m), five satellites' ECEF positions (m)
    and the gnss_raw.csv columns of the range residual tests."""
    p = gr.ecef_from_geodetic(math.radians(44.23), math.radians(-76.5), 40.0)
    sats = [np.array(s) for s in ([2.0e7, 0.5e7, 1.2e7], [0.3e7, -2.1e7, 1.5e7],
                                  [1.1e7, -1.0e7, 2.1e7], [2.2e7, -0.4e7, 1.0e7],
                                  [0.9e7, -1.6e7, 1.9e7])]
    names = ["time_s", "prn", "sat_x_m", "sat_y_m", "sat_z_m", "sat_clock_corr_m",
             "iono_corr_m", "tropo_corr_m", "pseudorange_m", "elevation"]
    return p, sats, names


def test_residuals_against_the_reference_show_one_satellites_error():
    """tools.kingston.raw --residuals: ranges made from a known position, the receiver's
    clock 1234.5 m and the corrections gnss_raw.csv carries, one satellite 5 m long: less
    the median the others are 0 and it is +5 m (1 mm: float64); less that satellite's,
    the others are -5 m; an epoch without it is left out."""
    p, sats, names = _five_satellites()
    rows = []
    for t in (100.0, 101.0):
        for i, s in enumerate(sats):
            if t == 101.0 and i == 4:
                continue
            geo = float(np.linalg.norm(s - p))
            corr = (20.0 + i, 3.0 + 0.5 * i, 2.5 + 0.3 * i)  # clock, iono, tropo
            pr = geo + 1234.5 - corr[0] + corr[1] + corr[2] + (5.0 if i == 4 else 0.0)
            rows.append((t, i + 1, *s, *corr, pr, 0.5))
    raw = np.array(rows, dtype=[(n, float) for n in names])
    ref = np.array([(99.0, 44.23, -76.5, 40.0), (102.0, 44.23, -76.5, 40.0)],
                   dtype=[(n, float) for n in ("time_s", "lat_deg", "lon_deg", "height_m")])
    med = kraw.residuals(raw, ref, 90.0, 0.0, 20.0)
    assert [t for t, _, _ in med] == [10.0, 11.0]
    for prn, _, v in med[0][1]:
        assert v == pytest.approx(5.0 if prn == 5 else 0.0, abs=1e-3)
    rel = kraw.residuals(raw, ref, 90.0, 0.0, 20.0, relative_to=5)
    assert len(rel) == 1
    for prn, _, v in rel[0][1]:
        assert v == pytest.approx(0.0 if prn == 5 else -5.0, abs=1e-3)


def test_correction_switches_show_the_common_and_the_satellite_steps():
    """tools.kingston.raw --corrections: five epochs in one correction set (ionospheric
    corrections negative), five in the other (positive) whose ranges are 4 m longer for
    every satellite and 1 m more for one, and whose satellite clock corrections are 2 m
    more: one switch; across it the median steps 4 m and the satellites less it
    sqrt(1/5) m RMS (one of five by 1 m), the clock corrections 2 m; within a set nothing
    moves (1 mm: float64); that satellite's mean is 0 in one set and +1 m in the other."""
    p, sats, names = _five_satellites()
    rows = []
    for t in np.arange(100.0, 110.0):
        second = t >= 105.0
        for i, s in enumerate(sats):
            geo = float(np.linalg.norm(s - p))
            corr = (20.0 + i + (2.0 if second else 0.0), (2.0 if second else -3.0) + 0.1 * i,
                    2.5)
            step = (4.0 + (1.0 if i == 4 else 0.0)) if second else 0.0
            pr = geo + 1234.5 - corr[0] + corr[1] + corr[2] + step
            rows.append((t, i + 1, *s, *corr, pr, 0.5))
    raw = np.array(rows, dtype=[(n, float) for n in names])
    ref = np.array([(99.0, 44.23, -76.5, 40.0), (111.0, 44.23, -76.5, 40.0)],
                   dtype=[(n, float) for n in ("time_s", "lat_deg", "lon_deg", "height_m")])
    res = kraw.residuals(raw, ref, 90.0, 0.0, 30.0)
    sw = kraw.correction_switches(raw, res, 90.0)
    assert sw["epochs"] == {-1: 5, 1: 5}
    assert sw["switches"] == 1
    assert sw["pairs"] == (5, 40)
    assert sw["common_m"][0] == pytest.approx(4.0, abs=1e-3)
    assert sw["common_m"][1] == pytest.approx(0.0, abs=1e-3)
    assert sw["sat_m"][0] == pytest.approx(math.sqrt(0.2), abs=1e-3)
    assert sw["sat_m"][1] == pytest.approx(0.0, abs=1e-3)
    assert sw["clock_m"] == pytest.approx((2.0, 0.0), abs=1e-9)
    assert sw["mean_m"][5][-1] == (pytest.approx(0.0, abs=1e-3), 5)
    assert sw["mean_m"][5][1] == (pytest.approx(1.0, abs=1e-3), 5)
    assert sw["mean_m"][1][1] == (pytest.approx(0.0, abs=1e-3), 5)
    assert kraw.correction_set(np.array([0.0, 0.0])) == 0
    assert kraw.correction_set(np.array([-1.0, 2.0])) == 2


def test_rate_residuals_against_the_reference_show_the_drift_and_one_satellite():
    """tools.kingston.raw --residuals --rates: Dopplers made from the reference's velocity
    (12 m/s east, 5 m/s north, 0.5 m/s up, through its ENU axes), the satellites' own and a
    receiver clock drift of 85.25 m/s, one satellite's rate 0.5 m/s fast: less the median
    the others are 0 and it is +0.5 m/s, the median is the drift (1e-6 m/s: float64)."""
    lat, lon = math.radians(44.23), math.radians(-76.5)
    p = gr.ecef_from_geodetic(lat, lon, 40.0)
    v_enu = np.array([12.0, 5.0, 0.5])
    v_rx = gr.enu_axes(lat, lon).T @ v_enu
    _, sats, _ = _five_satellites()
    vels = [np.array(v) for v in ([100.0, -2000.0, 3000.0], [-1500.0, 200.0, 2500.0],
                                  [2500.0, 800.0, -1200.0], [-300.0, 3100.0, 100.0],
                                  [1800.0, -1800.0, 900.0])]
    names = ["time_s", "prn", "sat_x_m", "sat_y_m", "sat_z_m", "sat_vx_mps", "sat_vy_mps",
             "sat_vz_mps", "doppler", "elevation"]
    rows = []
    for i, (s, v) in enumerate(zip(sats, vels)):
        u = (s - p) / np.linalg.norm(s - p)
        # the file's velocity is in the transmit time's axes, the positions in the
        # receive time's: the rate is made with it turned by omega tau
        v_rx_axes = gr.rotate_z(v, WGS84_OMEGA_IE_RPS * np.linalg.norm(s - p) / gr.C_MPS)
        rate = float(u @ (v_rx_axes - v_rx)) + 85.25 + (0.5 if i == 2 else 0.0)
        rows.append((100.0, i + 1, *s, *v, -rate / gr.GPS_L1_WAVELENGTH_M, 0.5))
    raw = np.array(rows, dtype=[(n, float) for n in names])
    cols = ("time_s", "lat_deg", "lon_deg", "height_m", "ve_mps", "vn_mps", "vu_mps")
    ref = np.array([(99.0, 44.23, -76.5, 40.0, *v_enu), (102.0, 44.23, -76.5, 40.0, *v_enu)],
                   dtype=[(n, float) for n in cols])
    (t, per, med), = kraw.residuals(raw, ref, 90.0, 0.0, 20.0, rates=True)
    assert t == 10.0
    assert med == pytest.approx(85.25, abs=1e-6)
    for prn, _, v in per:
        assert v == pytest.approx(0.5 if prn == 3 else 0.0, abs=1e-6)


def test_epoch_to_epoch_correlation_of_the_residuals():
    """tools.kingston.raw --rates: an AR(1) residual of coefficient 0.8 from one 1-s epoch to
    the next shows about 0.8 (4000 pairs over two satellites: the estimate's standard error
    is about 0.006, the bound 0.05); white residuals about 0; a residual beyond 1 m/s is
    left out and counted (both pairs it is in)."""
    rng = np.random.default_rng(3)
    for phi in (0.8, 0.0):
        x = np.zeros((2, 2001))
        for i in range(1, 2001):
            x[:, i] = phi * x[:, i - 1] + 0.05 * rng.standard_normal(2)
        x[1, 1000] = 5.0
        rows = [(float(i), [(7, 40.0, float(x[0, i])), (9, 60.0, float(x[1, i]))], 0.0)
                for i in range(2001)]
        r, n, out = kraw.epoch_to_epoch_correlation(rows)
        assert r == pytest.approx(phi, abs=0.05)
        assert (n, out) == (3998, 2)
