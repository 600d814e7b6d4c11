"""A recorded drive through the firmware: `make drive DATA=folder VEHICLE=profile`.

    python -m tools.drive --data data/comma2k19-rav4 --vehicle toyota_rav4_2017 [args...]
    python -m tools.drive --data data/kingston-2008 [args...]

Picks the recording's runner by what the folder holds: a car's whole bus (car_bus.log,
comma2k19: tools/comma2k19/run.py, output in out/drive-<folder>/) or the Kingston 2008
files (tools/kingston/run.py, native profile, output in out/kingston/). Further arguments
go to the runner.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True)
    ap.add_argument("--vehicle", default="native")
    a, rest = ap.parse_known_args(argv)
    data = Path(a.data)
    if (data / "car_bus.log").exists():
        from tools.comma2k19 import run
        return run.main(["--data", str(data), "--vehicle", a.vehicle,
                         "--out", f"out/drive-{data.name}", *rest])
    if (data / "imu.csv").exists() and (data / "odometer.csv").exists():
        if a.vehicle != "native":
            print("drive: the Kingston drive has navecu's own frames: VEHICLE=native",
                  file=sys.stderr)
            return 2
        from tools.kingston import run
        return run.main(["--data", str(data), *rest])
    print(f"drive: {data}: neither a car's bus recording (car_bus.log) nor the Kingston "
          "files", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
