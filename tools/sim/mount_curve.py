"""The IMU mounted at yaw 90 deg, upside down (roll 180 deg) and pitched 30 deg in the
default drive (tools/sim/scenarios/mount-*.toml), per IMU grade:

- configured (--imu-mount-deg, the true angles): the navigation accuracy beside the
  aligned IMU's (the same drive, the same seeds);
- automatic (--imu-mount-source automatic, firmware/app/mount_est.h): the estimate's
  error against the true angles as a function of time, from NAV_Calibration pages 1 and 2
  (once a second, on the log's time: the simulator's --can-log runs are on the IMU time),
  plotted to OUT/mount_curve.png and summarised at 1..5 min; the navigation accuracy
  once the estimate has converged and navigation started with it.

Usage: python -m tools.sim.mount_curve [--imu automotive --imu mid-grade] [--out DIR]
Writes OUT/mount_curve.json and OUT/mount_curve.png (default out/sim/mount_curve)."""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from tools import navecu_can as nc
from tools.sim import run as sim_run
from tools.sim import scenario

ROOT = Path(__file__).resolve().parents[2]
CASES = {"aligned": "default", "yaw90": "mount-yaw90", "upside-down": "mount-upside-down",
         "pitch30": "mount-pitch30"}
MINUTES = (1, 2, 3, 4, 5)


def read_mount_pages(path) -> dict:
    """NAV_Calibration pages 1 and 2 of a navecu output log as arrays on the log's time
    (one pair a second): t_s, roll/pitch/yaw (deg), sigma_rp/sigma_yaw (deg), excitation,
    state."""
    import can
    db = nc.load_db()
    cal_id = db.get_message_by_name("NAV_Calibration").frame_id
    rows, cur = [], {}
    with can.LogReader(str(path)) as reader:
        for msg in reader:
            if msg.arbitration_id != cal_id:
                continue
            sig = db.decode_message(cal_id, bytes(msg.data), decode_choices=False)
            if sig["CalPage"] == 1:
                cur = {"t_s": float(msg.timestamp), "roll": sig["MountRoll"],
                       "pitch": sig["MountPitch"], "yaw": sig["MountYaw"]}
            elif sig["CalPage"] == 2 and cur:
                cur.update({"sigma_rp": sig["MountSigmaRollPitch"],
                            "sigma_yaw": sig["MountSigmaYaw"],
                            "excitation": sig["MountExcitation"], "state": sig["MountState"]})
                rows.append(cur)
                cur = {}
    keys = ("t_s", "roll", "pitch", "yaw", "sigma_rp", "sigma_yaw", "excitation", "state")
    return {k: np.array([r[k] for r in rows], dtype=float) for k in keys}


def wrap_deg(x):
    return (np.asarray(x) + 180.0) % 360.0 - 180.0


def estimate_errors(pages: dict, truth: dict) -> dict:
    """The estimate's error (deg) against the true angles. Roll 180 and -180 are one
    install; yaw is compared wrapped."""
    return {"t_s": pages["t_s"],
            "roll": wrap_deg(pages["roll"] - truth["roll_deg"]),
            "pitch": wrap_deg(pages["pitch"] - truth["pitch_deg"]),
            "yaw": wrap_deg(pages["yaw"] - truth["yaw_deg"])}


def at_minutes(err: dict, pages: dict) -> list:
    out = []
    for m in MINUTES:
        i = int(np.searchsorted(err["t_s"], 60.0 * m))
        if i >= len(err["t_s"]):
            out.append({"min": m, "available": False})
            continue
        out.append({"min": m, "t_s": float(err["t_s"][i]),
                    "roll_err_deg": round(float(err["roll"][i]), 3),
                    "pitch_err_deg": round(float(err["pitch"][i]), 3),
                    "yaw_err_deg": round(float(err["yaw"][i]), 3),
                    "sigma_rp_deg": float(pages["sigma_rp"][i]),
                    "sigma_yaw_deg": float(pages["sigma_yaw"][i]),
                    "excitation_m2ps3": float(pages["excitation"][i]),
                    "state": int(pages["state"][i])})
    return out


def accuracy(rep: dict) -> dict:
    h = rep.get("horizontal_error_m") or {}
    hd = rep.get("heading_error_deg") or {}
    return {"navigation_start_s": rep.get("navigation_start_s"),
            "horizontal_rms_m": h.get("rms"), "horizontal_p95_m": h.get("p95"),
            "horizontal_max_m": h.get("max"), "heading_rms_deg": hd.get("rms"),
            "final_error_pct_of_distance": rep.get("final_error_pct_of_distance")}


def run_case(scen_name: str, imu: str, mount: str, out: Path, extra: list,
             reuse: bool = False) -> dict:
    if reuse and (out / "report.json").exists() and (out / "nav.log").exists():
        return json.loads((out / "report.json").read_text())
    args = ["--scenario", scen_name, "--imu", imu, "--mount", mount, "--out", str(out)]
    args += [f"--fw-arg={x}" for x in extra]
    rc = sim_run.main(args)
    if rc != 0:
        raise SystemExit(f"mount_curve: the simulation {scen_name} {imu} {mount} failed")
    return json.loads((out / "report.json").read_text())


def plot(curves: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for (label, err) in curves.items():
        for ax, k in zip(axes, ("roll", "pitch", "yaw")):
            ax.plot(err["t_s"] / 60.0, err[k], label=label, lw=1)
    for ax, k, lim in zip(axes, ("roll", "pitch", "yaw"), (1.0, 1.0, 2.0)):
        ax.axhline(lim, color="k", ls=":", lw=0.8)
        ax.axhline(-lim, color="k", ls=":", lw=0.8)
        ax.set_ylim(-3 * lim, 3 * lim)
        ax.set_ylabel(f"{k} error (deg)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    axes[-1].set_xlabel("time since the start (min)")
    axes[0].set_title("automatic mounting estimate - true mounting (dotted: 1 deg roll/pitch, "
                      "2 deg yaw)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--imu", action="append", default=None,
                    help="IMU preset(s) of tools/sim/sensors.py (default automotive, mid-grade)")
    ap.add_argument("--out", default=str(ROOT / "out" / "sim" / "mount_curve"))
    ap.add_argument("--fw-arg", action="append", default=[],
                    help="a firmware option for the automatic runs (repeat)")
    ap.add_argument("--reuse", action="store_true",
                    help="take a case's run from its folder when it has one (report.json)")
    ap.add_argument("--cases", default=",".join(CASES),
                    help="comma-separated subset of " + ",".join(CASES))
    a = ap.parse_args(argv)
    grades = a.imu or ["automotive", "mid-grade"]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    cases = [c for c in a.cases.split(",") if c]
    result, curves = {"grades": {}}, {}
    for imu in grades:
        g = result["grades"].setdefault(imu, {})
        for case in cases:
            scen_name = CASES[case]
            truth = scenario.load(scen_name)["imu_mounting"]
            modes = ["configured"] if case == "aligned" else ["configured", "automatic"]
            if case == "aligned":
                modes.append("automatic")
            row = {"truth_deg": {k: truth[k] for k in ("roll_deg", "pitch_deg", "yaw_deg")}}
            for mode in modes:
                d = out / imu / f"{case}-{mode}"
                rep = run_case(scen_name, imu, mode, d, a.fw_arg if mode == "automatic" else [],
                               a.reuse)
                row[mode] = accuracy(rep)
                if mode == "automatic":
                    pages = read_mount_pages(d / "nav.log")
                    err = estimate_errors(pages, truth)
                    curves[f"{imu} {case}"] = err
                    conv = np.flatnonzero(pages["state"] >= 2)
                    row[mode]["converged_at_s"] = float(pages["t_s"][conv[0]]) if conv.size else None
                    row[mode]["estimate_at_min"] = at_minutes(err, pages)
                    row[mode]["estimate_final_deg"] = {
                        k: round(float(pages[k][-1]), 3) for k in ("roll", "pitch", "yaw")}
            g[case] = row
    plot(curves, out / "mount_curve.png")
    (out / "mount_curve.json").write_text(json.dumps(result, indent=2))
    for imu, g in result["grades"].items():
        print(f"== {imu}")
        for case, row in g.items():
            c = row["configured"]
            print(f"  {case:12s} configured: rms {c['horizontal_rms_m']:.2f} m, p95 "
                  f"{c['horizontal_p95_m']:.2f} m, heading rms {c['heading_rms_deg']:.2f} deg")
            au = row.get("automatic")
            if au:
                print(f"  {'':12s} automatic: converged at {au['converged_at_s']} s, rms "
                      f"{au['horizontal_rms_m']:.2f} m, p95 {au['horizontal_p95_m']:.2f} m, "
                      f"heading rms {au['heading_rms_deg']:.2f} deg")
                for e in au["estimate_at_min"]:
                    if e.get("available", True):
                        print(f"  {'':14s}{e['min']} min: roll {e['roll_err_deg']:+.3f} pitch "
                              f"{e['pitch_err_deg']:+.3f} yaw {e['yaw_err_deg']:+.3f} deg "
                              f"(sigma {e['sigma_rp_deg']:.3f}/{e['sigma_yaw_deg']:.3f}, "
                              f"state {e['state']})")
    print(f"mount_curve: {out / 'mount_curve.json'}, {out / 'mount_curve.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
