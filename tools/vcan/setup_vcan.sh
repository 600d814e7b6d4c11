#!/usr/bin/env bash
# setup_vcan.sh [IFACE] - create and bring up a virtual CAN interface (default vcan0) on a
# normal Linux machine (`make vcan`). Idempotent: an existing, up vcan is left alone.
# Uses sudo when not root. Kernels without CAN (these CI machines, PLATFORM.md) cannot do
# this: use tools/vcan/with_vcan.sh, which falls back to User-Mode Linux.
set -euo pipefail

IFACE=${1:-vcan0}
die() { echo "setup_vcan: ERROR: $*" >&2; exit 1; }
SUDO=
if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null 2>&1 || die "not root and no sudo: run as root"
    SUDO=sudo
fi
command -v ip >/dev/null 2>&1 || die "'ip' not found (Debian: apt-get install iproute2)"

if d=$(ip -details link show dev "$IFACE" 2>/dev/null); then
    grep -q vcan <<<"$d" || die "$IFACE exists but is not a vcan interface:"$'\n'"$d"
else
    if ! grep -qw vcan /proc/modules 2>/dev/null; then
        command -v modprobe >/dev/null 2>&1 || die "'modprobe' not found (Debian: apt-get install kmod)"
        $SUDO modprobe vcan 2>/dev/null \
            || echo "setup_vcan: 'modprobe vcan' failed - trying anyway (vcan may be built in)" >&2
    fi
    if ! err=$($SUDO ip link add dev "$IFACE" type vcan 2>&1); then
        die "'ip link add dev $IFACE type vcan' failed: $err
  This kernel ($(uname -r)) has no vcan (CONFIG_CAN_VCAN). Run the CAN tests through
  tools/vcan/with_vcan.sh instead (it boots User-Mode Linux: apt-get install user-mode-linux kmod)."
    fi
fi
$SUDO ip link set up dev "$IFACE" || die "'ip link set up dev $IFACE' failed"
echo "setup_vcan: $IFACE is up"
ip -brief link show dev "$IFACE"
