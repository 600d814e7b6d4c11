"""The application image for the bootloader (issue #19): the package format and the
validity marker, the Python side of firmware/boot/boot_image.h (the constants below must
equal its #defines: tests/python/test_flash_tool.py checks them).

    python3 -m tools.navecu_pkg pack build/target/navecu.bin build/target/navecu.pkg [--version N]
    python3 -m tools.navecu_pkg mark build/target/navecu.bin build/target/navecu-app.bin
    python3 -m tools.navecu_pkg info build/target/navecu.pkg

- the image: the application's raw binary from 0x0800C000 (objcopy -O binary), its marker
  slot (16 bytes after the 392-byte vector table) erased (0xFF), as the linker leaves it;
- its CRC-32: zlib.crc32 of the image (the bootloader's firmware/diag/crc32.c);
- pack: a 32-byte header (magic, format version, header length, load address, image
  length, image CRC-32, software version, reserved, the header's CRC-32) and the image: what
  `navecu_flash.py flash` sends over UDS;
- mark: the image with the validity marker programmed into its slot, as the bootloader
  writes it after checkMemory: a factory image for `make flash` (openocd), which then
  starts without a UDS download.
Standard library only (the target build runs it without the virtual environment).
"""
from __future__ import annotations

import argparse
import struct
import sys
import zlib
from dataclasses import dataclass
from pathlib import Path

# firmware/boot/boot_image.h
BOOT_APP_START = 0x0800C000
BOOT_APP_SIZE = 0x14000
BOOT_NVM_START = 0x08004000
BOOT_NVM_SIZE = 0x8000
BOOT_VECTORS_LEN = 392
BOOT_MARKER_ADDR = BOOT_APP_START + BOOT_VECTORS_LEN
BOOT_MARKER_LEN = 16
BOOT_MARKER_MAGIC = 0x4F42564E
BOOT_PKG_MAGIC = 0x4B50564E
BOOT_PKG_VERSION = 1
BOOT_PKG_HEADER_LEN = 32

_HEAD = struct.Struct("<IHHIIIII")  # 28 bytes, then the header's CRC-32
MARKER_OFFSET = BOOT_MARKER_ADDR - BOOT_APP_START


class PackageError(ValueError):
    """Not an image or package the bootloader would take."""


def crc32(data: bytes) -> int:
    return zlib.crc32(data) & 0xFFFFFFFF


@dataclass
class Package:
    image: bytes
    address: int = BOOT_APP_START
    sw_version: int = 0

    @property
    def crc(self) -> int:
        return crc32(self.image)


def check_image(image: bytes) -> None:
    """The rules the bootloader applies (firmware/boot/boot.c), before anything is sent."""
    if not BOOT_VECTORS_LEN + BOOT_MARKER_LEN + 4 <= len(image) <= BOOT_APP_SIZE:
        raise PackageError(f"image of {len(image)} bytes: the application region holds "
                           f"{BOOT_VECTORS_LEN + BOOT_MARKER_LEN + 4}..{BOOT_APP_SIZE}")
    slot = image[MARKER_OFFSET:MARKER_OFFSET + BOOT_MARKER_LEN]
    if slot != b"\xff" * BOOT_MARKER_LEN:
        raise PackageError("the marker slot (0x0800C188..0x0800C197) is not erased: not an "
                           "image linked with boards/stm32f405/stm32f405.ld, or already marked")
    sp, pc = struct.unpack_from("<II", image, 0)
    if not (0x20000008 <= sp <= 0x20020000 and sp % 4 == 0):
        raise PackageError(f"initial stack pointer 0x{sp:08X} is not in SRAM")
    if not (pc & 1 and BOOT_MARKER_ADDR + BOOT_MARKER_LEN <= (pc & ~1)
            < BOOT_APP_START + len(image)):
        raise PackageError(f"reset vector 0x{pc:08X} is not a Thumb address in the image")


def pack(pkg: Package) -> bytes:
    check_image(pkg.image)
    head = _HEAD.pack(BOOT_PKG_MAGIC, BOOT_PKG_VERSION, BOOT_PKG_HEADER_LEN, pkg.address,
                      len(pkg.image), pkg.crc, pkg.sw_version, 0)
    return head + struct.pack("<I", crc32(head)) + pkg.image


def unpack(data: bytes) -> Package:
    if len(data) < BOOT_PKG_HEADER_LEN:
        raise PackageError("shorter than a package header")
    magic, ver, hlen, addr, n, crc, sw, _ = _HEAD.unpack_from(data, 0)
    if magic != BOOT_PKG_MAGIC:
        raise PackageError("not a navecu package (magic)")
    if ver != BOOT_PKG_VERSION or hlen != BOOT_PKG_HEADER_LEN:
        raise PackageError(f"package format {ver} with a {hlen}-byte header: not supported")
    if struct.unpack_from("<I", data, 28)[0] != crc32(data[:28]):
        raise PackageError("package header CRC-32 wrong")
    image = data[hlen:]
    if len(image) != n:
        raise PackageError(f"package says {n} image bytes, holds {len(image)} (truncated?)")
    if crc32(image) != crc:
        raise PackageError("package image CRC-32 wrong (corrupted)")
    if addr != BOOT_APP_START:
        raise PackageError(f"load address 0x{addr:08X}, the application's is 0x{BOOT_APP_START:08X}")
    check_image(image)
    return Package(image=image, address=addr, sw_version=sw)


def marker(length: int, crc: int) -> bytes:
    return struct.pack("<IIII", BOOT_MARKER_MAGIC, length, crc,
                       ~(BOOT_MARKER_MAGIC ^ length ^ crc) & 0xFFFFFFFF)


def mark(image: bytes) -> bytes:
    """The image with its validity marker, as the bootloader leaves the flash."""
    check_image(image)
    return (image[:MARKER_OFFSET] + marker(len(image), crc32(image))
            + image[MARKER_OFFSET + BOOT_MARKER_LEN:])


def _read_hex(path: Path) -> bytes:
    """An Intel HEX file's bytes in the application region (0xFF in gaps). Every line but
    blank ones must be a whole record with its checksum, and the file must end with the
    end-of-file record: a HEX file cut short otherwise loads as a shorter image whose own
    CRC-32 the bootloader would accept."""
    mem: dict[int, int] = {}
    base = 0
    try:
        lines = path.read_text(encoding="ascii").splitlines()
    except UnicodeDecodeError as e:
        raise PackageError(f"{path}: not an Intel HEX file (byte 0x{e.object[e.start]:02X} "
                           f"at offset {e.start} is not ASCII)") from None
    ended = False
    for lineno, ln in enumerate(lines, 1):
        ln = ln.strip()
        if not ln:
            continue
        where = f"{path}:{lineno}"
        if ended:
            raise PackageError(f"{where}: a record after the end-of-file record")
        if not ln.startswith(":"):
            raise PackageError(f"{where}: not an Intel HEX record (no ':')")
        try:
            rec = bytes.fromhex(ln[1:])
        except ValueError:
            raise PackageError(f"{where}: not an Intel HEX record (not whole hexadecimal bytes)") from None
        if len(rec) < 5 or len(rec) != rec[0] + 5:
            raise PackageError(f"{where}: record of {len(rec)} bytes, its length field says "
                               f"{rec[0] + 5 if rec else '?'} (truncated?)")
        n, addr, kind = rec[0], (rec[1] << 8) | rec[2], rec[3]
        if sum(rec) & 0xFF:
            raise PackageError(f"{where}: checksum error in {ln[:20]}")
        want = {1: 0, 2: 2, 3: 4, 4: 2, 5: 4}.get(kind)
        if want is not None and n != want:
            raise PackageError(f"{where}: a type {kind:02X} record of {n} data bytes (the "
                               f"format's {want})")
        if kind == 0:
            for i, b in enumerate(rec[4:4 + n]):
                mem[base + addr + i] = b
        elif kind == 1:
            ended = True
        elif kind == 4:
            base = ((rec[4] << 8) | rec[5]) << 16
        elif kind == 2:
            base = ((rec[4] << 8) | rec[5]) << 4
        elif kind not in (3, 5):
            raise PackageError(f"{where}: unknown record type {kind:02X}")
    if not ended:
        raise PackageError(f"{path}: no end-of-file record (:00000001FF): truncated")
    addrs = [a for a in mem if a >= BOOT_APP_START]
    if [a for a in mem if a < BOOT_APP_START]:
        raise PackageError(f"{path}: bytes below 0x{BOOT_APP_START:08X} (the bootloader or "
                           "the NVM): not an application image")
    if not addrs:
        raise PackageError(f"{path}: no bytes in the application region")
    end = max(addrs) + 1
    return bytes(mem.get(a, 0xFF) for a in range(BOOT_APP_START, end))


def load(path: str | Path) -> Package:
    """A package (.pkg), an Intel HEX file (.hex) or a raw binary for 0x0800C000."""
    p = Path(path)
    data = p.read_bytes()
    if data[:4] == struct.pack("<I", BOOT_PKG_MAGIC):
        return unpack(data)
    image = _read_hex(p) if p.suffix.lower() == ".hex" else data
    check_image(image)
    return Package(image=image)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("pack", help="image -> package")
    a.add_argument("image")
    a.add_argument("out")
    a.add_argument("--version", type=lambda s: int(s, 0), default=0)
    m = sub.add_parser("mark", help="image -> factory image with the validity marker")
    m.add_argument("image")
    m.add_argument("out")
    i = sub.add_parser("info", help="what a package, HEX or BIN holds")
    i.add_argument("file")
    args = ap.parse_args(argv)
    try:
        if args.cmd == "pack":
            pkg = load(args.image)
            pkg.sw_version = args.version
            Path(args.out).write_bytes(pack(pkg))
            print(f"navecu_pkg: {args.out}: {len(pkg.image)} bytes at 0x{pkg.address:08X}, "
                  f"CRC-32 0x{pkg.crc:08X}")
        elif args.cmd == "mark":
            pkg = load(args.image)
            Path(args.out).write_bytes(mark(pkg.image))
            print(f"navecu_pkg: {args.out}: {len(pkg.image)} bytes at 0x{pkg.address:08X} "
                  f"with the marker (CRC-32 0x{pkg.crc:08X})")
        else:
            pkg = load(args.file)
            print(f"{args.file}: {len(pkg.image)} bytes at 0x{pkg.address:08X}, CRC-32 "
                  f"0x{pkg.crc:08X}, software version {pkg.sw_version}")
    except (PackageError, OSError) as e:
        print(f"navecu_pkg: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
