"""navecu's fault memory (firmware/app/dtc.c behind UDS 0x19 / 0x14) live on vcan0, against
udsoncan over can-isotp: the IMU goes silent, its DTC is read confirmed with udsoncan's
ReadDTCInformation, cleared with ClearDiagnosticInformation and read gone.

tools/vcan/dtc_check.py runs build/host/navecu --can vcan0 inside one
tools/vcan/with_vcan.sh run and plays the tester; the verdicts are here. Like
tests/python/test_uds_live.py: under CI a missing vcan fails, elsewhere these tests are
skipped loudly. The expected numbers come from firmware/app/dtc.toml (through
tools/gen_dtc.py) and ISO 14229-1 Annex D, not from the firmware.
"""

import pytest

from test_vcan_harness import live_check
from tools import gen_dtc

IMU_STALE = "D10187"  # U1101-87
NO_GNSS = "D10287"    # U1102-87


@pytest.fixture(scope="module")
def r():
    return live_check("tools.vcan.dtc_check")


def test_the_table_is_the_generated_one():
    by_flag = {d["flag"]: f"{d['number']:06X}" for d in gen_dtc.load()}
    assert by_flag["IMU_STALE"] == IMU_STALE and by_flag["NO_GNSS"] == NO_GNSS


def test_supported_dtcs_before_any_test(r):
    assert r["availability"] == 0x7F
    # every DTC of the table, none tested yet: testNotCompleted since clear and this cycle
    assert r["supported_before"] == {f"{d['number']:06X}": 0x50 for d in gen_dtc.load()}


def test_imu_alive_is_not_a_fault(r):
    assert r["imu_frames"] == 200  # 1 s of pairs at 100 Hz
    # nothing fails: NO_GNSS (there is no GNSS on this bus) is debounced, it fails after
    # 60 s of it (dtc.toml; before, 1 s of it was a failure: TF TFTOC PDTC TFSLC)
    assert r["failing_with_imu"] == {}


def test_silent_imu_confirmed(r):
    # TF, TFTOC, PDTC, CDTC, TFSLC: failing for over its 2 s confirm time
    assert r["confirmed"] == {IMU_STALE: 0x2F}
    assert r["confirmed_count"] == 1
    assert r["confirmed_format"] == 0x00  # SAE_J2012-DA_DTCFormat_00


def test_cleared_then_gone(r):
    assert r["clear_positive"]
    assert r["confirmed_after_clear"] == {}
    assert all(s & 0x08 == 0 for s in r["all_after_clear"].values())
    # the diagnostic frames never reached navecu's own dispatch
    assert "navecu: foreign frames (not read, not refused): 0" in r["firmware_summary"]
