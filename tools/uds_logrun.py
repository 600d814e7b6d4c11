"""The host executable on a CAN log as a UDS peer: a python-can bus whose every sent frame
is appended to a candump log that build/host/navecu then replays (`--can-log IN --out
OUT`), the frames it answered on the response ID handed back as received.

    from tools.uds_logrun import LogRunnerBus
    bus = LogRunnerBus(navecu="build/host/navecu", session="build/uds/session.log",
                       nvm="build/uds/nvm.bin")

The firmware's output depends only on its input (host_sim/main.c), so replaying the whole
history of the session after each frame gives the same answers to the earlier frames and
the new answers after the last one: the ISO-TP flow (FF, the ECU's FC, the CFs; the
ECU's FF, the tester's FC, its CFs) and the UDS exchange run unchanged in can-isotp and
udsoncan above this bus. A frame is stamped with the wall clock (strictly increasing),
so the server's timers (S3, the security delay, the ISO-TP timeouts) see real time;
advance() lets bus time pass without waiting and inject() adds other nodes' frames (an
IMU for a while, then silent: a fault to read as a DTC).

Power-on session: the history lives in the `session` log (a temporary one when None),
so successive tool runs with the same session continue one power-on of the ECU (a
configuration written in RAM is still there); deleting it (`power_cycle()`) is a power
cycle. NVM: each replay boots from the image the session started with (SESSION.nvm0, a
copy of `nvm` at the session's first frame) and the image after the latest replay is
copied to `nvm`: the next session boots from what this one stored.

The replay costs one navecu run per frame sent (a few milliseconds on a short log, the
history growing with the session). `navecu_args` go to every run (e.g. `--imu-rate-hz
100`); they are part of the power-on configuration.
"""
from __future__ import annotations

import os
import queue
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Optional, Sequence

import can

from tools import navecu_can as nc

ROOT = Path(__file__).resolve().parent.parent
NAVECU = ROOT / "build" / "host" / "navecu"
IFACE = "can0"  # the interface name written into the log


class LogRunError(can.CanError):
    """navecu refused or failed on the session log (its stderr in the message)."""


def _read_log(path: Path) -> list:
    """The frames of a session or output log; a malformed line (a session log edited by
    hand, or cut by a crash) skipped and its count said on stderr, as navecu skips it
    (navecu_can.read_log), not a python-can traceback."""
    if not path.exists() or path.stat().st_size == 0:
        return []
    return nc.read_log(path)


def _write_log(path: Path, frames: Sequence[can.Message]) -> None:
    with path.open("w", encoding="ascii") as f:
        for m in frames:
            data = m.data.hex().upper()
            ident = f"{m.arbitration_id:08X}" if m.is_extended_id else f"{m.arbitration_id:03X}"
            f.write(f"({m.timestamp:.6f}) {IFACE} {ident}#{data}\n")


class LogRunnerBus(can.BusABC):
    """A python-can bus that answers with navecu replaying the session's log."""

    def __init__(self, channel: str = "logrun", *, navecu: Optional[str] = None,
                 response_id: int = 0x7A8, session: Optional[str] = None,
                 nvm: Optional[str] = None, navecu_args: Sequence[str] = (),
                 timeout_s: float = 60.0, **kwargs):
        super().__init__(channel=channel, **kwargs)
        self.channel_info = "navecu on a CAN log"
        self.navecu = str(navecu or os.environ.get("NAVECU_BIN", NAVECU))
        if not Path(self.navecu).exists():
            raise LogRunError(f"{self.navecu} missing: make build/host/navecu")
        self.response_id = response_id
        self.navecu_args = list(navecu_args)
        self.timeout_s = timeout_s
        self._tmp = tempfile.TemporaryDirectory(prefix="uds_logrun_")
        work = Path(self._tmp.name)
        self.session = Path(session) if session else work / "session.log"
        self.session.parent.mkdir(parents=True, exist_ok=True)
        self.nvm = Path(nvm) if nvm else None
        self._nvm0 = Path(str(self.session) + ".nvm0")
        self._out = work / "out.log"
        self._nvm_run = work / "nvm.bin"
        self._rx: queue.Queue = queue.Queue()
        self._offset = 0.0  # bus time ahead of the wall clock (advance, inject)
        self.runs = 0
        self.history = _read_log(self.session)
        # the answers already given in this session are not handed over again; with no
        # history, the run on an empty log checks navecu_args before any request
        try:
            self._seen = len(self._answers(self._replay()))
        except Exception:
            self.shutdown()
            raise

    # ---------------------------------------------------------------- the replay
    def _replay(self) -> list:
        _write_log(self.session, self.history)
        cmd = [self.navecu, "--can-log", str(self.session), "--out", str(self._out)]
        if self.nvm is not None:
            if not self._nvm0.exists():  # the session's start: its power-on image
                if self.nvm.exists():
                    shutil.copyfile(self.nvm, self._nvm0)
                else:
                    self._nvm0.write_bytes(b"")
            if self._nvm0.stat().st_size:
                shutil.copyfile(self._nvm0, self._nvm_run)
            elif self._nvm_run.exists():
                self._nvm_run.unlink()  # a fresh NVM: navecu creates it
            cmd += ["--nvm", str(self._nvm_run)]
        cmd += self.navecu_args
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=self.timeout_s)
        self.runs += 1
        if proc.returncode not in (0,) or not self._out.exists():
            raise LogRunError(f"navecu exit {proc.returncode} on {self.session}: "
                              f"{proc.stderr.strip()[-600:]}")
        if self.nvm is not None and self._nvm_run.exists():
            shutil.copyfile(self._nvm_run, self.nvm)
        return _read_log(self._out)

    def _answers(self, frames: list) -> list:
        return [m for m in frames if m.arbitration_id == self.response_id
                and not m.is_extended_id]

    # ---------------------------------------------------------------- python-can
    def _now(self) -> float:
        """The next frame's time: the wall clock (plus what advance() added), after the
        last frame of the history by at least 1 ms."""
        last = self.history[-1].timestamp if self.history else 0.0
        return round(max(time.time() + self._offset, last + 1e-3), 6)

    def advance(self, seconds: float) -> None:
        """Let `seconds` of bus time pass before the next frame, without waiting for them
        (the bus is silent meanwhile: timers run out, a silent sender is seen silent)."""
        self._offset += seconds

    def inject(self, frames: Sequence[can.Message]) -> None:
        """Other nodes' frames (an IMU, a GNSS receiver) into the session: each at now plus
        its own timestamp (seconds from the first), replayed with the tester's from the
        next one on; the bus time moves on to the last of them."""
        if not frames:
            return
        t0, base = frames[0].timestamp, self._now()
        for m in frames:
            self.history.append(can.Message(timestamp=round(base + m.timestamp - t0, 6),
                                            arbitration_id=m.arbitration_id,
                                            is_extended_id=m.is_extended_id,
                                            data=bytes(m.data), dlc=m.dlc))
        self._offset += max(0.0, self.history[-1].timestamp - time.time() - self._offset)

    def send(self, msg: can.Message, timeout: Optional[float] = None) -> None:
        self.history.append(can.Message(timestamp=self._now(), arbitration_id=msg.arbitration_id,
                                        is_extended_id=msg.is_extended_id,
                                        data=bytes(msg.data), dlc=msg.dlc))
        answers = self._answers(self._replay())
        for m in answers[self._seen:]:
            self._rx.put(m)
        self._seen = len(answers)

    def _recv_internal(self, timeout: Optional[float]):
        try:
            return self._rx.get(timeout=timeout if timeout is not None else 1e6), False
        except queue.Empty:
            return None, False

    def power_cycle(self) -> None:
        """End the power-on session: the next frame boots navecu afresh (from `nvm`)."""
        self.history = []
        self._seen = 0
        for p in (self.session, self._nvm0):
            if p.exists():
                p.unlink()

    def shutdown(self) -> None:
        super().shutdown()
        self._tmp.cleanup()
