"""navecu's fault memory live on vcan0, as a tester with udsoncan sees it (run inside
with_vcan.sh).

    python -m tools.vcan.dtc_check [--navecu build/host/navecu]

Starts build/host/navecu --can vcan0, reads the supported DTCs with udsoncan's
ReadDTCInformation (over can-isotp), sends IMU samples of a car at rest for 1 s (E2E-valid
pairs, tools/gen_stationary_log.py's), then lets the IMU go silent: after 0.5 s of bus
time NAV_Status carries IMU_STALE and its DTC U1101-87 fails, 2 s later it is confirmed.
The tester reads it (0x19 01, 02), clears every DTC (0x14 FF FF FF, default session) and
reads it gone. Prints one JSON object of what every step answered, for
tests/python/test_dtc_live.py to judge (the DTC numbers and status bytes as integers).
Exit status 0 when every step ran, 1 when one raised, 2 with "NO VCAN" when vcan0 is missing.
"""
import sys
import time

import can
import isotp
import udsoncan
from udsoncan.client import Client
from udsoncan.connections import PythonIsoTpConnection

from tools import gen_stationary_log
from tools.vcan.uds_check import IFACE, check_main, start_navecu, stop_navecu

IMU_S = 1.0        # IMU samples sent before the silence
CONFIRM_WAIT_S = 3.5  # 0.5 s until stale + 2 s confirm time + margin


def dtcs_of(resp):
    return {int(d.id): int(d.status.get_byte_as_int()) for d in resp.service_data.dtcs}


def send_imu(bus, seconds):
    """IMU pairs of a car at rest at 100 Hz, paced in real time; the frames sent."""
    frames = [m for m in gen_stationary_log.generate(duration_s=seconds)
              if m.arbitration_id in (0x100, 0x101)]
    t0 = time.monotonic()
    for m in frames:
        delay = m.timestamp - (time.monotonic() - t0)
        if delay > 0:
            time.sleep(delay)
        bus.send(can.Message(arbitration_id=m.arbitration_id, data=m.data,
                             is_extended_id=False))
    return len(frames)


def run(binary):
    r = {}
    proc = start_navecu(binary)
    bus = can.Bus(interface="socketcan", channel=IFACE,
                  can_filters=[{"can_id": 0x7A8, "can_mask": 0x7FF, "extended": False}])
    tx = can.Bus(interface="socketcan", channel=IFACE, receive_own_messages=False)
    addr = isotp.Address(isotp.AddressingMode.Normal_11bits, txid=0x7A0, rxid=0x7A8)
    stack = isotp.CanStack(bus, address=addr, params={"blocking_send": False, "tx_padding": 0xCC})
    conn = PythonIsoTpConnection(stack)
    config = dict(udsoncan.configs.default_client_config)
    config.update({"request_timeout": 5.0, "p2_timeout": 2.0, "p2_star_timeout": 6.0})
    try:
        with Client(conn, config=config) as c:
            sup = c.get_supported_dtc()
            r["availability"] = int(sup.service_data.status_availability.get_byte_as_int())
            r["supported_before"] = dtcs_of(sup)
            r["imu_frames"] = send_imu(tx, IMU_S)
            live = c.get_dtc_by_status_mask(0x01)  # failing now, with the IMU alive
            r["failing_with_imu"] = dtcs_of(live)
            time.sleep(CONFIRM_WAIT_S)             # the IMU silent
            n = c.get_number_of_dtc_by_status_mask(0x08)
            r["confirmed_count"] = n.service_data.dtc_count
            r["confirmed_format"] = int(n.service_data.dtc_format)
            r["confirmed"] = dtcs_of(c.get_dtc_by_status_mask(0x08))
            r["clear_positive"] = c.clear_dtc(0xFFFFFF).positive
            r["confirmed_after_clear"] = dtcs_of(c.get_dtc_by_status_mask(0x08))
            r["all_after_clear"] = dtcs_of(c.get_supported_dtc())
    finally:
        stack.stop()
        bus.shutdown()
        tx.shutdown()
        r["firmware_summary"] = stop_navecu(proc)
    # JSON keys are strings: the DTC numbers as hex
    for k in ("supported_before", "failing_with_imu", "confirmed", "confirmed_after_clear",
              "all_after_clear"):
        r[k] = {f"{d:06X}": s for d, s in r[k].items()}
    return r


def main(argv=None):
    return check_main(__doc__, run, argv)


if __name__ == "__main__":
    sys.exit(main())
