"""Flash the application over CAN through the bootloader (issue #19; docs/target.md "The
bootloader", docs/can.md "Programming"): UDS on ISO-TP with udsoncan and can-isotp, the
same client set-up as tools/navecu_uds.py.

    python -m tools.navecu_flash [--channel vcan0 | --pipe "CMD ..."] flash IMAGE
    make flash-can IMAGE=build/target/navecu.pkg BUS=can0

IMAGE: a package (tools/navecu_pkg.py: header with length and CRC-32), an Intel HEX file or
a raw binary for 0x0800C000. The sequence (each step's negative response ends the run with
its NRC named, exit status 1):
  10 02        programming session (from the application: 7F 10 78, it resets into the
               bootloader, which answers 50 02; from the bootloader: 50 02 at once)
  27 01 / 02   SecurityAccess, the key of firmware/diag/uds.h (navecu_uds.key_of_seed)
  31 01 FF00   eraseMemory 44 0800C000 <length> (7F 31 78 while the sectors erase)
  34 00 44     RequestDownload 0800C000 <length>: the block length the bootloader takes
  36 nn ..     TransferData, counter 1, 2, .. FF, 00, ..; a block without an answer is sent
               again with the same counter (--retries): the bootloader acknowledges a repeat
               of its last block without writing it again
  37           RequestTransferExit
  31 01 FF01   checkProgrammingDependencies <CRC-32>: the bootloader checks the flash and
               writes the validity marker
  11 01        ECUReset: the bootloader starts the new application
--pipe runs a program that speaks candump lines on stdin/stdout (build/host/navecu-boot, the
bootloader's logic on the host): the tests' bus, and a dry run without an ECU.
Exit status: 0 done, 1 a negative response, 2 no answer / transport, 3 a bad image, 4 usage.
"""
from __future__ import annotations

import argparse
import logging
import queue
import shlex
import struct
import subprocess
import sys
import threading
import time
from typing import Optional

import can

from tools import navecu_pkg, navecu_uds

SESSION_PROGRAMMING = 0x02
RID_ERASE = 0xFF00
RID_CHECK = 0xFF01
ALFID = 0x44
DID_BOOT_COUNTERS = 0xFD00  # the bootloader's counts since it started (docs/can.md)
BOOT_COUNTERS = ("blocks programmed", "repeated", "sectors erased", "checks refused",
                 "flash errors", "responsePendings")


class PipeBus(can.BusABC):
    """A python-can bus to a program on candump lines: what is sent goes to its stdin
    (stamped with the wall clock), its stdout lines are received. When the program has
    ended (a power cut in the tests) the bus is silent: sends go nowhere."""

    def __init__(self, channel: str = "pipe", *, cmd: list, **kwargs):
        super().__init__(channel=channel, **kwargs)
        self.channel_info = f"pipe to {cmd[0]}"
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, bufsize=1)
        self._rx: queue.Queue = queue.Queue()
        self._last = 0.0
        self.sent_lines: list = []      # every line written to the program (a tester log)
        self.received_lines: list = []  # every frame line it wrote
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for ln in self.proc.stdout:
            p = ln.split()
            if len(p) != 3 or "#" not in p[2]:
                continue
            ident, data = p[2].split("#", 1)
            self.received_lines.append(ln)
            self._rx.put(can.Message(timestamp=float(p[0].strip("()")),
                                     arbitration_id=int(ident, 16),
                                     is_extended_id=len(ident) > 3,
                                     data=bytes.fromhex(data)))

    def send(self, msg: can.Message, timeout: Optional[float] = None) -> None:
        if self.proc.poll() is not None:
            return  # the ECU is off
        t = max(time.time(), self._last + 1e-6)
        self._last = t
        ident = f"{msg.arbitration_id:08X}" if msg.is_extended_id else f"{msg.arbitration_id:03X}"
        line = f"({t:.6f}) can0 {ident}#{bytes(msg.data).hex().upper()}\n"
        self.sent_lines.append(line)
        try:
            self.proc.stdin.write(line)
            self.proc.stdin.flush()
        except (BrokenPipeError, ValueError):
            pass

    def _recv_internal(self, timeout: Optional[float]):
        try:
            return self._rx.get(timeout=timeout if timeout is not None else 1e6), False
        except queue.Empty:
            return None, False

    def shutdown(self) -> None:
        super().shutdown()
        if self.proc.poll() is None:
            try:
                self.proc.stdin.close()
                self.proc.wait(timeout=5)
            except (subprocess.TimeoutExpired, BrokenPipeError, OSError):
                self.proc.kill()
                self.proc.wait()
        self.stderr = self.proc.stderr.read() if self.proc.stderr else ""


class Flasher:
    """The programming sequence on an open udsoncan Client (importable: tests, scripts)."""

    def __init__(self, client, out=sys.stderr, retries: int = 3, max_block: int = 0):
        self.c = client
        self.out = out
        self.retries = retries
        self.max_block = max_block  # 0: what the bootloader announces
        self.repeats = 0
        client.config.setdefault("data_identifiers", {})[DID_BOOT_COUNTERS] = \
            navecu_uds.Raw(4 * len(BOOT_COUNTERS))

    def say(self, text: str) -> None:
        print(text, file=self.out, flush=True)

    def transfer(self, seq: int, block: bytes) -> None:
        from udsoncan.exceptions import TimeoutException
        for attempt in range(self.retries + 1):
            try:
                self.c.transfer_data(seq, block)
                return
            except TimeoutException:
                if attempt == self.retries:
                    raise
                self.repeats += 1
                self.say(f"flash: block {seq:#04x} unanswered, sent again "
                         f"({attempt + 1}/{self.retries})")

    def boot_counters(self) -> Optional[dict]:
        """The bootloader's counts (DID 0xFD00), or None from a bootloader without them
        (navecu-boot 1 answers 7F 22 31) or with no answer: the image is flashed and
        checked by then, so this never fails the flash."""
        from udsoncan.exceptions import NegativeResponseException, TimeoutException
        try:
            raw = self.c.read_data_by_identifier(DID_BOOT_COUNTERS).service_data.values[
                DID_BOOT_COUNTERS]
        except (NegativeResponseException, TimeoutException) as e:
            self.say(f"flash: the bootloader's counts not read ({e}): an older bootloader")
            return None
        return dict(zip(BOOT_COUNTERS, struct.unpack(f">{len(BOOT_COUNTERS)}I", raw)))

    def flash(self, pkg: navecu_pkg.Package) -> dict:
        from udsoncan import MemoryLocation
        image, addr = pkg.image, pkg.address
        t0 = time.monotonic()
        self.c.change_session(SESSION_PROGRAMMING)
        self.c.unlock_security_access(navecu_uds.SECURITY_LEVEL)
        self.say(f"flash: programming session, unlocked; erasing {len(image)} bytes at "
                 f"0x{addr:08X}")
        self.c.start_routine(RID_ERASE, data=struct.pack(">BII", ALFID, addr, len(image)))
        r = self.c.request_download(MemoryLocation(addr, len(image), address_format=32,
                                                   memorysize_format=32))
        block = r.service_data.max_length - 2
        if self.max_block:
            block = min(block, self.max_block)
        n_blocks = (len(image) + block - 1) // block
        self.say(f"flash: {n_blocks} blocks of up to {block} bytes")
        shown = -1
        for i in range(n_blocks):
            self.transfer((i + 1) & 0xFF, image[i * block:(i + 1) * block])
            pct = (i + 1) * 100 // n_blocks
            if pct // 10 != shown:
                shown = pct // 10
                self.say(f"flash: {min((i + 1) * block, len(image))}/{len(image)} bytes "
                         f"({pct} %)")
        self.c.request_transfer_exit()
        self.c.start_routine(RID_CHECK, data=struct.pack(">I", pkg.crc))
        self.say(f"flash: the bootloader checked CRC-32 0x{pkg.crc:08X} and marked the image "
                 "valid")
        counts = self.boot_counters()
        if counts is not None:
            self.say("flash: the bootloader counted " + ", ".join(
                f"{n} {k}" for k, n in list(counts.items())[:5]))
        self.c.ecu_reset(1)
        dt = time.monotonic() - t0
        self.say(f"flash: done, {len(image)} bytes in {dt:.1f} s ({len(image) / dt / 1024:.1f} "
                 f"KiB/s), {self.repeats} blocks sent again; ECUReset: the application starts")
        return {"bytes": len(image), "blocks": n_blocks, "seconds": dt,
                "repeats": self.repeats, "boot_counters": counts}


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="navecu_flash", description=__doc__.split("\n\n")[0])
    req, rsp = navecu_uds.default_ids()
    ap.add_argument("--interface", default="socketcan")
    ap.add_argument("--channel", default="vcan0")
    ap.add_argument("--pipe", default=None, help="a program on candump lines instead of a bus")
    ap.add_argument("--request-id", type=lambda s: int(s, 0), default=req)
    ap.add_argument("--response-id", type=lambda s: int(s, 0), default=rsp)
    ap.add_argument("--timeout", type=float, default=1.0, help="P2 of each request (s)")
    ap.add_argument("--p2-star", type=float, default=10.0,
                    help="wait after a 0x78 responsePending (erase, check, reset) (s)")
    ap.add_argument("--retries", type=int, default=3, help="a TransferData sent again")
    ap.add_argument("--max-block", type=int, default=0, help="data bytes per TransferData")
    ap.add_argument("-v", "--verbose", action="store_true")
    sub = ap.add_subparsers(dest="cmd")
    f = sub.add_parser("flash", help="write IMAGE (.pkg, .hex or .bin) through the bootloader")
    f.add_argument("image")
    return ap


def open_bus(a):
    if a.pipe:
        return PipeBus(cmd=shlex.split(a.pipe))
    try:
        return can.Bus(interface=a.interface, channel=a.channel,
                       can_filters=[{"can_id": a.response_id, "can_mask": 0x7FF,
                                     "extended": False}])
    except (OSError, can.CanError, ValueError, ImportError) as e:
        raise navecu_uds.TransportError(f"cannot open {a.interface} channel {a.channel}: "
                                        f"{e}") from None


def main(argv=None, out=sys.stderr) -> int:
    ap = parser()
    try:
        a = ap.parse_args(argv)
    except SystemExit as e:
        return navecu_uds.EXIT_OK if e.code == 0 else navecu_uds.EXIT_USAGE
    if a.cmd != "flash":
        ap.print_usage(out)
        return navecu_uds.EXIT_USAGE
    if not a.verbose:
        logging.getLogger("UdsClient").setLevel(logging.CRITICAL)
        logging.getLogger("isotp").setLevel(logging.CRITICAL)
    try:
        pkg = navecu_pkg.load(a.image)
    except (navecu_pkg.PackageError, OSError) as e:
        print(f"navecu_flash: bad image: {e}", file=out)
        return navecu_uds.EXIT_INPUT
    print(f"navecu_flash: {a.image}: {len(pkg.image)} bytes at 0x{pkg.address:08X}, CRC-32 "
          f"0x{pkg.crc:08X}", file=out)
    client = None
    try:
        bus = open_bus(a)
        client = navecu_uds.client_on_bus(bus, a.request_id, a.response_id, a.timeout, {},
                                          p2_star_s=a.p2_star)
        Flasher(client, out=out, retries=a.retries, max_block=a.max_block).flash(pkg)
        return navecu_uds.EXIT_OK
    except Exception as e:  # noqa: BLE001 - sorted into the exit statuses
        return navecu_uds.report(e, out, "navecu_flash")
    finally:
        if client is not None:
            navecu_uds.close_client(client)


if __name__ == "__main__":
    sys.exit(main())
