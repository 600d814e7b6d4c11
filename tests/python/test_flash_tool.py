"""The flash path of issue #19 end to end: tools/navecu_pkg.py against
firmware/boot/boot_image.h, tools/navecu_flash.py on udsoncan + can-isotp against the
bootloader's logic (build/host/navecu-boot: firmware/boot/boot.c on the host, a file as the
application's flash), power cuts at every TransferData block boundary, in the marker and in
each erase, and the flashed file booted on QEMU by the ECU's bootloader (boot.elf), whose
application then answers a drive byte for byte as the host build does.

What this does not show: the ECU bootloader's own CAN and flash driver at work (QEMU has
neither a CAN controller nor a flash controller; docs/target.md "The bootloader").
"""
from __future__ import annotations

import io
import os
import re
import shutil
import struct
import subprocess
from pathlib import Path

import pytest

from tools import navecu_can, navecu_flash, navecu_pkg, navecu_uds
from tools.target import qemu_run

from test_nvm_qemu import drive_log  # tests/python is on sys.path (rootdir-less modules)

ROOT = Path(__file__).resolve().parents[2]
BOOT_HOST = Path(os.environ.get("NAVECU_BOOT_BIN", ROOT / "build" / "host" / "navecu-boot"))
NAVECU = Path(os.environ.get("NAVECU_BIN", ROOT / "build" / "host" / "navecu"))
TARGET = ROOT / "build" / "target"
APP_BIN = TARGET / "navecu-qemu.bin"  # the QEMU application, its marker slot erased
BOOT_ELF = TARGET / "boot.elf"
HEADER = ROOT / "firmware" / "boot" / "boot_image.h"


def _need(*paths):
    missing = [str(p) for p in paths if not Path(p).exists()]
    if missing:
        msg = "needs " + ", ".join(missing) + " (make build/host/navecu-boot target-qemu)"
        if os.environ.get("CI"):
            pytest.fail(msg + " - CI is set, so this is a failure")
        pytest.skip(msg)


def header_defines() -> dict:
    """boot_image.h's #defines, evaluated where they are numbers or sums of them."""
    out = {}
    for name, expr in re.findall(r"^#define (BOOT_\w+) (.+?)(?:\s*/\*.*)?$", HEADER.read_text(),
                                 re.M):
        expr = re.sub(r"\b(0x[0-9A-Fa-f]+|\d+)u\b", r"\1", expr)
        try:
            out[name] = eval(expr, {}, dict(out))  # noqa: S307 - our own header
        except (NameError, SyntaxError):
            pass
    return out


def test_package_constants_equal_the_c_header():
    d = header_defines()
    names = [n for n in dir(navecu_pkg) if n.startswith("BOOT_")]
    assert len(names) >= 11
    for n in names:
        assert d[n] == getattr(navecu_pkg, n), n


def test_package_round_trip_and_refusals(tmp_path):
    _need(APP_BIN)
    image = APP_BIN.read_bytes()
    data = navecu_pkg.pack(navecu_pkg.Package(image=image, sw_version=7))
    assert len(data) == navecu_pkg.BOOT_PKG_HEADER_LEN + len(image)
    back = navecu_pkg.unpack(data)
    assert back.image == image and back.sw_version == 7 and back.crc == navecu_pkg.crc32(image)
    with pytest.raises(navecu_pkg.PackageError, match="corrupted"):
        bad = bytearray(data)
        bad[-100] ^= 1
        navecu_pkg.unpack(bytes(bad))
    with pytest.raises(navecu_pkg.PackageError, match="truncated"):
        navecu_pkg.unpack(data[:-10])
    with pytest.raises(navecu_pkg.PackageError, match="marker slot"):
        navecu_pkg.pack(navecu_pkg.Package(image=navecu_pkg.mark(image)))
    # the HEX file of the same image loads to the same bytes
    hexfile = tmp_path / "app.hex"
    subprocess.run(["arm-none-eabi-objcopy", "-I", "binary", "-O", "ihex",
                    "--change-addresses", "0x0800C000", str(APP_BIN), str(hexfile)], check=True)
    assert navecu_pkg.load(hexfile).image == image


def _hex_records(image: bytes, address: int = navecu_pkg.BOOT_APP_START) -> list:
    """Intel HEX lines of image at address (16-byte data records, one extended linear
    address record, the end-of-file record last): what objcopy -O ihex writes."""
    def rec(kind: int, addr: int, data: bytes) -> str:
        body = bytes([len(data), addr >> 8, addr & 0xFF, kind]) + data
        return ":" + (body + bytes([-sum(body) & 0xFF])).hex().upper()
    lines = [rec(4, 0, (address >> 16).to_bytes(2, "big"))]
    lines += [rec(0, (address + i) & 0xFFFF, image[i:i + 16]) for i in range(0, len(image), 16)]
    return lines + [rec(1, 0, b"")]


def test_hex_file_cut_short_or_corrupt_is_refused_with_its_line(tmp_path):
    # a small image the bootloader's rules accept: SP in SRAM, reset vector after the slot
    image = bytearray(b"\x00" * 2048)
    struct.pack_into("<II", image, 0, 0x20020000, navecu_pkg.BOOT_MARKER_ADDR + 64 + 1)
    image[navecu_pkg.MARKER_OFFSET:navecu_pkg.MARKER_OFFSET + 16] = b"\xff" * 16
    lines = _hex_records(bytes(image))
    good = tmp_path / "good.hex"
    good.write_text("\n".join(lines) + "\n")
    assert navecu_pkg.load(good).image == bytes(image)
    cases = {
        # cut at a record boundary before its end: once loaded as a shorter image whose
        # own CRC-32 the bootloader would have accepted
        "end-of-file record": lines[:-20],
        "good.hex:31: record of": lines[:30] + [lines[30][:21]],     # cut mid-record
        "good.hex:11: not an Intel HEX record": lines[:10] + [":10ZZ"] + lines[10:],
        "good.hex:6: record of": lines[:5] + [":01"] + lines[5:],
        "good.hex:3: not an Intel HEX record": lines[:2] + ["garbage"] + lines[2:],
        "after the end-of-file record": lines + lines[1:2],
        # an extended linear address of no bytes (an IndexError), of one (its checksum
        # byte taken for the address)
        "good.hex:2: a type 04 record of 0 data bytes": lines[:1] + [":00000004FC"] + lines[1:],
        "good.hex:2: a type 04 record of 1 data bytes": lines[:1] + [":0100000408F3"] + lines[1:],
    }
    for what, body in cases.items():
        bad = tmp_path / "good.hex"
        bad.write_text("\n".join(body) + "\n")
        with pytest.raises(navecu_pkg.PackageError, match=re.escape(what)):
            navecu_pkg.load(bad)
    good.write_bytes(("\n".join(lines[:5]) + "\n").encode() + b"\xff\xfe\n")
    with pytest.raises(navecu_pkg.PackageError, match="not an Intel HEX file"):
        navecu_pkg.load(good)
    # the command line says it and fails, no traceback
    good.write_text("\n".join(lines[:-20]) + "\n")
    assert navecu_pkg.main(["info", str(good)]) == 1
    out = io.StringIO()
    assert navecu_flash.main(["--pipe", "true", "flash", str(good)], out=out) == \
        navecu_uds.EXIT_INPUT
    assert "truncated" in out.getvalue()


def flash_tool(flash: Path, image: Path, *boot_args, timeout=1.0, retries=3) -> tuple:
    """navecu_flash.py against navecu-boot on `flash`: (exit status, its report)."""
    pipe = f"{BOOT_HOST} --flash {flash} " + " ".join(boot_args)
    out = io.StringIO()
    rc = navecu_flash.main(["--pipe", pipe, "--timeout", str(timeout), "--retries",
                            str(retries), "flash", str(image)], out=out)
    return rc, out.getvalue()


def power_on(flash: Path) -> str:
    """The bootloader's decision at reset on that flash (its stderr line)."""
    r = subprocess.run([str(BOOT_HOST), "--flash", str(flash)], input="", capture_output=True,
                       text=True, timeout=10)
    assert r.returncode == 0, r.stderr
    return r.stderr.strip()


def test_flash_over_uds_marks_the_image_and_it_starts(tmp_path):
    _need(BOOT_HOST, APP_BIN)
    flash = tmp_path / "flash.bin"
    assert "no valid application" in power_on(flash)  # erased flash: the bootloader stays
    pkg = tmp_path / "app.pkg"
    assert navecu_pkg.main(["pack", str(APP_BIN), str(pkg)]) == 0
    rc, text = flash_tool(flash, pkg)
    assert rc == 0, text
    assert "done, " in text and "ECUReset" in text
    image = APP_BIN.read_bytes()
    # the flash holds the image with the marker, the rest erased
    assert flash.read_bytes()[:len(image)] == navecu_pkg.mark(image)
    assert set(flash.read_bytes()[len(image):]) == {0xFF}
    assert "application valid (%d bytes): started" % len(image) in power_on(flash)


def test_every_negative_response_named(tmp_path):
    _need(BOOT_HOST, APP_BIN)
    flash = tmp_path / "flash.bin"

    class WrongDigest(navecu_pkg.Package):
        @property
        def crc(self):
            return navecu_pkg.crc32(self.image) ^ 1

    bus = navecu_flash.PipeBus(cmd=[str(BOOT_HOST), "--flash", str(flash)])
    client = navecu_uds.client_on_bus(bus, 0x7A0, 0x7A8, 1.0, {}, p2_star_s=5.0)
    out = io.StringIO()
    try:
        with pytest.raises(Exception) as e:
            navecu_flash.Flasher(client, out=out).flash(WrongDigest(image=APP_BIN.read_bytes()))
        err = io.StringIO()
        assert navecu_uds.report(e.value, err, "navecu_flash") == navecu_uds.EXIT_NRC
        assert err.getvalue().strip() == ("navecu_flash: negative response 0x72 "
                                          "generalProgrammingFailure to RoutineControl (0x31)")
        # TransferData without a download: the bootloader's 0x24, named
        with pytest.raises(Exception) as e:
            client.transfer_data(1, b"\x00")
        err = io.StringIO()
        navecu_uds.report(e.value, err, "navecu_flash")
        assert "0x24 requestSequenceError to TransferData (0x36)" in err.getvalue()
    finally:
        navecu_uds.close_client(client)
    assert "no valid application" in power_on(flash)
    # a bad image is refused before anything is sent
    bad = tmp_path / "bad.bin"
    bad.write_bytes(b"\x00" * 1000)
    rc, text = flash_tool(flash, bad)
    assert rc == navecu_uds.EXIT_INPUT and "bad image: the marker slot" in text


def test_power_cut_at_every_block_boundary_then_reflash(tmp_path):
    """The old image valid; the new one flashed with the power cut after every whole
    TransferData block (510 bytes, as on the ECU), half-way into the first block, in
    the marker, and half-way through each of the two sector erases: after each the
    bootloader finds no valid image and stays; then a complete flash starts."""
    _need(BOOT_HOST, APP_BIN)
    image = APP_BIN.read_bytes()
    flash = tmp_path / "flash.bin"
    rc, text = flash_tool(flash, APP_BIN)
    assert rc == 0, text
    block = 510
    cuts = [["--cut-after", str(n)] for n in range(0, len(image), block)]
    cuts += [["--cut-after", "255"], ["--cut-after", str(len(image) + 8)],
             ["--cut-in-erase", "0"], ["--cut-in-erase", "1"]]
    for cut in cuts:
        rc, text = flash_tool(flash, APP_BIN, *cut, timeout=0.3, retries=0)
        assert rc == navecu_uds.EXIT_TRANSPORT, (cut, text)
        assert "no valid application" in power_on(flash), cut
    print(f"power cuts: {len(cuts)} ({len(image) // block + 1} block boundaries, mid-block, "
          "marker, 2 erases): never started after one")
    rc, text = flash_tool(flash, APP_BIN)
    assert rc == 0, text
    assert "started" in power_on(flash)


def test_lost_answer_block_sent_again(tmp_path):
    """A TransferData whose answer does not come is sent again with its counter; the
    bootloader acknowledges the repeat without writing (firmware/boot/boot.c)."""
    _need(BOOT_HOST, APP_BIN)
    flash = tmp_path / "flash.bin"
    bus = navecu_flash.PipeBus(cmd=[str(BOOT_HOST), "--flash", str(flash)])
    dropped = []
    real_recv = bus._recv_internal

    def lossy(timeout):
        m, f = real_recv(timeout)
        if m is not None and m.data[:3] == b"\x02\x76\x05" and not dropped:
            dropped.append(m)  # the answer to block 5, lost once
            return None, False
        return m, f

    bus._recv_internal = lossy
    client = navecu_uds.client_on_bus(bus, 0x7A0, 0x7A8, 0.5, {}, p2_star_s=5.0)
    out = io.StringIO()
    try:
        r = navecu_flash.Flasher(client, out=out).flash(
            navecu_pkg.Package(image=APP_BIN.read_bytes()))
    finally:
        navecu_uds.close_client(client)
    assert dropped and r["repeats"] == 1, out.getvalue()
    assert "started" in power_on(flash)


def qemu_from_flash(flash: Path, in_log: Path, out_log: Path, timeout: float):
    semi = f"enable=on,target=native,arg=navecu,arg={in_log},arg={out_log}"
    try:
        return subprocess.run(qemu_run.machine(flash, BOOT_ELF) + ["-semihosting-config", semi],
                              capture_output=True, text=True, timeout=timeout).returncode
    except subprocess.TimeoutExpired:
        return None


def test_flashed_file_boots_on_qemu_like_the_host(tmp_path):
    """The flash file written over UDS, loaded into QEMU's flash at 0x0800C000 behind the
    ECU's bootloader: it starts the application, whose output equals the host run's; after
    a power cut the bootloader does not start it (no output within 5 s)."""
    _need(BOOT_HOST, APP_BIN, BOOT_ELF, NAVECU)
    if shutil.which("qemu-system-arm") is None:
        pytest.skip("needs qemu-system-arm")
    flash = tmp_path / "flash.bin"
    rc, text = flash_tool(flash, APP_BIN)
    assert rc == 0, text
    log = drive_log(tmp_path)  # test_nvm_qemu's: the sim-clean drive
    subprocess.run([str(NAVECU), "--can-log", str(log), "--out", str(tmp_path / "host.out")],
                   check=True, capture_output=True)
    assert qemu_from_flash(flash, log, tmp_path / "qemu.out", 600) == 0
    host = navecu_can.data_driven((tmp_path / "host.out").read_text().splitlines())
    qemu = navecu_can.data_driven((tmp_path / "qemu.out").read_text().splitlines())
    assert len(host) > 1000 and qemu == host
    print(f"flashed over UDS, booted by boot.elf on QEMU: {len(qemu)} output frames identical "
          "to the host's")
    # a cut in the middle of the next download: the bootloader stays, nothing runs
    rc, _ = flash_tool(flash, APP_BIN, "--cut-after", "30000", timeout=0.3, retries=0)
    assert rc == navecu_uds.EXIT_TRANSPORT
    assert qemu_from_flash(flash, log, tmp_path / "cut.out", 5) is None
    assert not (tmp_path / "cut.out").exists()


BOOT_QEMU = TARGET / "boot-qemu.elf"


def boot_qemu(in_log: Path, out_log: Path, flash: Path, timeout: float = 300,
              extra=()) -> str:
    """The bootloader's logic on QEMU (boards/qemu/boot_main.c): the tester's log in, its
    answers out, the application's flash a semihosting file; extra: more arguments
    (request, cut-in-erase=N). Its console text."""
    semi = f"enable=on,target=native,arg=boot,arg={in_log},arg={out_log},arg={flash}"
    semi += "".join(f",arg={x}" for x in extra)
    r = subprocess.run(["qemu-system-arm", "-M", "netduinoplus2", "-nographic", "-monitor",
                        "none", "-serial", "none", "-semihosting-config", semi, "-kernel",
                        str(BOOT_QEMU)], capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout + r.stderr


def record_tester_log(tmp_path: Path) -> tuple:
    """A flash run of the QEMU application against the host bootloader on an erased flash:
    (the host's flash file, the bus with the tester's frames and the answers); the tester's
    frames also in tmp_path/tester.log, to replay to QEMU."""
    host_flash = tmp_path / "host.bin"
    bus = navecu_flash.PipeBus(cmd=[str(BOOT_HOST), "--flash", str(host_flash)])
    client = navecu_uds.client_on_bus(bus, 0x7A0, 0x7A8, 1.0, {}, p2_star_s=5.0)
    try:
        navecu_flash.Flasher(client, out=io.StringIO()).flash(
            navecu_pkg.Package(image=APP_BIN.read_bytes()))
    finally:
        navecu_uds.close_client(client)
    (tmp_path / "tester.log").write_text("".join(bus.sent_lines))
    return host_flash, bus


def test_qemu_bootloader_answers_as_the_host_and_survives_cuts(tmp_path):
    """The tester's frames of a flash run against the host bootloader, replayed to the
    bootloader built for the Cortex-M4F on QEMU: the same answers byte for byte and the
    same flash file, which the ECU's boot.elf then starts on QEMU. Then the same log cut
    at every TransferData block boundary (the power goes when the log ends): the next boot
    finds no valid application each time (checked on QEMU and by the same code on the
    host, for every cut)."""
    _need(BOOT_HOST, APP_BIN, BOOT_ELF, BOOT_QEMU)
    if shutil.which("qemu-system-arm") is None:
        pytest.skip("needs qemu-system-arm")
    host_flash, bus = record_tester_log(tmp_path)
    tester = bus.sent_lines
    qemu_flash = tmp_path / "qemu.bin"
    text = boot_qemu(tmp_path / "tester.log", tmp_path / "qemu.out", qemu_flash)
    assert "no valid application" in text and "application valid: started" in text, text
    assert (tmp_path / "qemu.out").read_text().splitlines() == \
        [ln.rstrip("\n") for ln in bus.received_lines]
    assert qemu_flash.read_bytes() == host_flash.read_bytes()
    print(f"QEMU bootloader: {len(tester)} tester frames, {len(bus.received_lines)} answers "
          "identical to the host build's, the same flash file")
    # the ECU bootloader starts what the QEMU bootloader wrote
    log = drive_log(tmp_path)
    assert qemu_from_flash(qemu_flash, log, tmp_path / "app.out", 600) == 0
    assert (tmp_path / "app.out").stat().st_size > 0
    # a power cut before each TransferData request (FF with SID 0x36 at its third byte),
    # before the exit and before the check
    def is_ff_of(ln: str, sid: int) -> bool:
        d = bytes.fromhex(ln.split("#")[1])
        return d[0] >> 4 == 1 and d[2] == sid or d[0] >> 4 == 0 and d[1] == sid
    cuts = [i for i, ln in enumerate(tester) if "7A0#" in ln and is_ff_of(ln, 0x36)]
    cuts += [i for i, ln in enumerate(tester) if "7A0#" in ln and (is_ff_of(ln, 0x37)
             or (is_ff_of(ln, 0x31) and "FF01" in ln))]
    n_blocks = -(-len(APP_BIN.read_bytes()) // 510)  # the ECU's blocks: 510 data bytes
    assert len(cuts) == n_blocks + 2
    for n, i in enumerate(cuts):
        flash = tmp_path / "cut.bin"
        if flash.exists():
            flash.unlink()
        (tmp_path / "cut.log").write_text("".join(tester[:i]))
        text = boot_qemu(tmp_path / "cut.log", tmp_path / "cut.out", flash)
        assert "end of the log" in text, text
        assert "no valid application" in power_on(flash), n
        empty = tmp_path / "empty.log"
        empty.write_text("")
        assert "no valid application" in boot_qemu(empty, tmp_path / "e.out", flash), n
    print(f"QEMU bootloader: {len(cuts)} power cuts (every block boundary, before the exit "
          "and before the check): never a valid application after one")


def test_qemu_power_cut_in_the_middle_of_an_erase(tmp_path):
    """On QEMU, a valid application being replaced (the bootloader entered on the
    application's programming request): the power goes half way through the first sector
    erase, then half way through the second (the other erase done): the next boot, on QEMU
    and by the host's check, finds no valid application and the bootloader stays; the same
    tester's complete flash then writes the image (the host's flash file byte for byte) and
    it starts."""
    _need(BOOT_HOST, APP_BIN, BOOT_QEMU)
    if shutil.which("qemu-system-arm") is None:
        pytest.skip("needs qemu-system-arm")
    host_flash, _ = record_tester_log(tmp_path)
    tester, empty = tmp_path / "tester.log", tmp_path / "empty.log"
    empty.write_text("")
    for n in (0, 1):
        flash = tmp_path / f"cut{n}.bin"
        flash.write_bytes(host_flash.read_bytes())
        assert "started" in power_on(flash)
        text = boot_qemu(tester, tmp_path / "cut.out", flash,
                         extra=("request", f"cut-in-erase={n}"))
        assert "programming requested" in text and "half way through an erase" in text, text
        assert "no valid application" in boot_qemu(empty, tmp_path / "e.out", flash), n
        assert "no valid application" in power_on(flash), n
        text = boot_qemu(tester, tmp_path / "re.out", flash)
        assert "application valid: started" in text, text
        assert flash.read_bytes() == host_flash.read_bytes()
    print("QEMU bootloader: power cut half way through each of the two sector erases: no "
          "valid application after it, the complete re-flash starts")


def test_counts_of_an_older_bootloader_do_not_fail_the_flash():
    """The bootloader's counts are read after the image is checked and marked valid: a
    bootloader without DID 0xFD00 (navecu-boot 1 answers 7F 22 31) or no answer must not
    turn that flash into a failure (a review's finding), and a newer one's 24 bytes are the
    six counts in order."""
    import udsoncan
    from udsoncan.exceptions import NegativeResponseException, TimeoutException
    from udsoncan.services import ReadDataByIdentifier

    class Client:
        def __init__(self, answer):
            self.config = {"data_identifiers": {}}
            self.answer = answer

        def read_data_by_identifier(self, did):
            assert did == navecu_flash.DID_BOOT_COUNTERS
            assert did in self.config["data_identifiers"]
            if isinstance(self.answer, Exception):
                raise self.answer
            r = udsoncan.Response(ReadDataByIdentifier, code=0)
            r.service_data = type("D", (), {"values": {did: self.answer}})()
            return r

    nrc = udsoncan.Response(ReadDataByIdentifier, code=0x31)
    for answer in (NegativeResponseException(nrc), TimeoutException("no answer")):
        out = io.StringIO()
        assert navecu_flash.Flasher(Client(answer), out=out).boot_counters() is None
        assert "not read" in out.getvalue() and "older bootloader" in out.getvalue()
    counts = navecu_flash.Flasher(Client(struct.pack(">6I", 128, 1, 2, 0, 0, 3)),
                                  out=io.StringIO()).boot_counters()
    assert list(counts.values()) == [128, 1, 2, 0, 0, 3]
    assert list(counts) == list(navecu_flash.BOOT_COUNTERS)
