#!/usr/bin/env bash
# with_vcan.sh CMD [ARGS...] - run CMD with a working SocketCAN vcan0 and exit with its status.
#
# 1. native: vcan0 already exists and is up, or the running kernel can create it
#    (`ip link add dev vcan0 type vcan`, root or passwordless sudo): CMD runs directly.
# 2. User-Mode Linux: the kernel has no CAN (these CI machines, docs: PLATFORM.md).
#    Debian's UML kernel boots with the host's root filesystem (hostfs), loads the CAN
#    modules, creates vcan0 and runs CMD in the caller's working directory with the
#    caller's essential environment. The guest sees the host's files, so host binaries
#    and the project's venv run unchanged. CMD's stdout, stderr and exit status come back
#    through files in a host temp directory and are printed here (stdout to stdout,
#    stderr to stderr, each complete after CMD ends; merge with `sh -c 'cmd 2>&1'` when
#    the interleaving matters). CMD's stdin is /dev/null.
# 3. neither: exit 77 with "SKIPPED: no vcan and no User-Mode Linux". The caller decides
#    whether that is a failure (CI must treat it as one).
#
# Exit status: CMD's own status; 77 = skipped (no vcan possible);
#              125 = the harness / UML itself failed (message says "UML FAILED"),
#              124 = UML run timed out.
# Environment (all optional):
#   NAVECU_VCAN_MODE     auto (default) | native | uml  - force one way (no fallback)
#   NAVECU_VCAN_TIMEOUT  seconds for the whole UML run, default 900
#   NAVECU_VCAN_UML      path of the UML kernel, default: linux.uml / linux on PATH
#   NAVECU_VCAN_UML_MEM  guest memory, default 1G
#   NAVECU_VCAN_PASSENV  extra variable names (space separated) to pass into the guest
#   NAVECU_VCAN_KEEP=1   keep the UML temp directory (init script, console log, outputs)
#   NAVECU_VCAN_VERBOSE=1  print the harness's progress and timings to stderr
#   NAVECU_VCAN_NICE     host nice value of the UML kernel, default -10 as root (0 = as the
#                        caller). The guest has one CPU for every process in it, and the
#                        firmware counts more than 70 ms between two IMU samples as lost
#                        samples (docs/live-can.md): a host busy with other work must not
#                        freeze the guest that long. Ignored when not root.
#   NAVECU_VCAN_CPU      host CPU the UML kernel is pinned to, default: the last one this
#                        process may use; "none" = not pinned. The guest has one CPU; its
#                        kernel and its processes are host threads that wake each other on
#                        every guest system call, and on a virtual machine a wake-up that
#                        goes to another virtual CPU can wait for the hypervisor (measured
#                        here: pinned, 4 500-5 000 frames/s and no pause over 30 ms; not
#                        pinned, 550-4 500 frames/s and pauses up to 0.8 s).
# Passed into the guest: PATH HOME CI USER LOGNAME LANG LC_ALL TZ TERM TMPDIR PYTHONPATH
# VIRTUAL_ENV PYTHONDONTWRITEBYTECODE, every NAVECU_* and those in NAVECU_VCAN_PASSENV.
set -uo pipefail

IFACE=vcan0
ME=with_vcan

say() { printf '%s: %s\n' "$ME" "$*" >&2; }
vsay() { [ "${NAVECU_VCAN_VERBOSE:-0}" = 1 ] && say "$@"; return 0; }

if [ $# -eq 0 ]; then
    echo "usage: $0 CMD [ARGS...]   (runs CMD with a SocketCAN $IFACE; see the header)" >&2
    exit 2
fi

mode=${NAVECU_VCAN_MODE:-auto}
case $mode in auto|native|uml) ;; *) say "NAVECU_VCAN_MODE=$mode: expected auto|native|uml"; exit 2;; esac

# ---------------------------------------------------------------- native vcan
as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"
    elif command -v sudo >/dev/null 2>&1; then sudo -n "$@"
    else return 1; fi
}

iface_is_vcan_up() {
    local d
    d=$(ip -details link show dev "$IFACE" 2>/dev/null) || return 1
    grep -q 'vcan' <<<"$d" && grep -q '[<,]UP[,>]' <<<"$d"
}

native_vcan() {
    command -v ip >/dev/null 2>&1 || return 1
    iface_is_vcan_up && return 0
    if ! ip link show dev "$IFACE" >/dev/null 2>&1; then
        as_root modprobe vcan >/dev/null 2>&1 || true   # built in or absent: ip says which
        as_root ip link add dev "$IFACE" type vcan >/dev/null 2>&1 || return 1
    fi
    as_root ip link set up dev "$IFACE" >/dev/null 2>&1 || return 1
    iface_is_vcan_up
}

if [ "$mode" != uml ]; then
    if native_vcan; then
        vsay "native $IFACE is up; running CMD directly"
        exec "$@"
    fi
    if [ "$mode" = native ]; then
        say "FAILED: NAVECU_VCAN_MODE=native but the running kernel cannot provide $IFACE"
        exit 125
    fi
    vsay "running kernel has no vcan ($(uname -r)); trying User-Mode Linux"
fi

# ---------------------------------------------------------------- User-Mode Linux
skip() {
    echo "**********************************************************************" >&2
    echo "SKIPPED: no vcan and no User-Mode Linux ($*)" >&2
    echo "  Debian: apt-get install user-mode-linux kmod  (or a kernel with vcan: make vcan)" >&2
    echo "**********************************************************************" >&2
    exit 77
}

uml=${NAVECU_VCAN_UML:-}
if [ -z "$uml" ]; then
    uml=$(command -v linux.uml 2>/dev/null || command -v linux 2>/dev/null || true)
    [ -n "$uml" ] || { [ -x /usr/bin/linux.uml ] && uml=/usr/bin/linux.uml; }
fi
[ -n "$uml" ] && [ -x "$uml" ] || skip "no UML kernel: linux.uml not found${NAVECU_VCAN_UML:+ at $NAVECU_VCAN_UML}"

# Modules live in /usr/lib/uml/modules/<guest kernel release>; the guest picks its own
# release at boot, here we only check that some release has vcan.
mods_ok=0
for d in /usr/lib/uml/modules/*/kernel; do
    [ -f "$d/drivers/net/can/vcan.ko" ] && [ -f "$d/net/can/can-raw.ko" ] && mods_ok=1
done
[ "$mods_ok" = 1 ] || skip "UML kernel $uml found but no vcan.ko under /usr/lib/uml/modules/*/kernel"
for t in insmod ip poweroff timeout; do
    command -v "$t" >/dev/null 2>&1 || skip "UML needs '$t' on the host (Debian: kmod, iproute2)"
done

# The guest sees the host's files through hostfs, except /proc, /sys and /dev (it mounts
# its own there), so the exchange directory must not live under those.
base=${TMPDIR:-/tmp}
case $base in /proc*|/sys*|/dev*|"") base=/tmp;; esac
work=$(mktemp -d "$base/navecu-vcan.XXXXXX") || { say "UML FAILED: cannot create a temp dir under $base"; exit 125; }
work=$(cd "$work" && pwd -P)

uml_pid=
cleanup() {
    [ -n "$uml_pid" ] && kill -TERM "$uml_pid" 2>/dev/null && wait "$uml_pid" 2>/dev/null
    if [ "${NAVECU_VCAN_KEEP:-0}" = 1 ]; then say "kept $work"; else rm -rf "$work"; fi
}
trap cleanup EXIT
trap 'say "interrupted"; exit 130' INT
trap 'say "terminated"; exit 143' TERM

# Environment file: bash-quoted exports, sourced by the guest's init.
{
    for v in PATH HOME CI USER LOGNAME LANG LC_ALL TZ TERM TMPDIR PYTHONPATH VIRTUAL_ENV \
             PYTHONDONTWRITEBYTECODE ${NAVECU_VCAN_PASSENV:-} $(compgen -e | grep '^NAVECU_' || true); do
        [ -n "${!v+x}" ] && printf 'export %s=%q\n' "$v" "${!v}"
    done
    printf 'cd -- %q || { echo "cannot cd to %q in the guest" >&2; exit 126; }\n' "$PWD" "$PWD"
    printf 'CMD=('; printf '%q ' "$@"; printf ')\n'
} > "$work/env.sh"

cat > "$work/init.sh" <<EOF
#!/bin/bash
# PID 1 of the UML guest, generated by tools/vcan/with_vcan.sh. Must always reach poweroff.
W=$(printf '%q' "$work")
stage() { echo "\$*" > "\$W/stage"; }
fail() { echo "\$*" > "\$W/setup_error"; poweroff -f; sleep 5; }
stage booted
mount -t proc proc /proc
mount -t sysfs sys /sys
mkdir -p /dev/shm /dev/pts && mount -t tmpfs -o mode=1777 shm /dev/shm && mount -t devpts devpts /dev/pts
echo \$(date +%s.%N) > "\$W/t_booted"
M=/usr/lib/uml/modules/\$(uname -r)/kernel
[ -d "\$M" ] || fail "no modules for the guest kernel \$(uname -r) in \$M"
stage modules
# order matters: can-raw needs can, vcan needs can-dev
for m in net/can/can.ko net/can/can-raw.ko drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko; do
    insmod "\$M/\$m" 2>>"\$W/setup_log" || fail "insmod \$M/\$m failed: \$(tail -1 "\$W/setup_log")"
done
stage vcan
ip link add dev $IFACE type vcan 2>>"\$W/setup_log" || fail "ip link add $IFACE failed"
ip link set up dev $IFACE 2>>"\$W/setup_log" || fail "ip link set up $IFACE failed"
ip link set lo up 2>/dev/null
stage cmd
(
    . "\$W/env.sh"
    exec "\${CMD[@]}"
) </dev/null >"\$W/stdout" 2>"\$W/stderr"
echo \$? > "\$W/status.tmp" && mv "\$W/status.tmp" "\$W/status"
stage done
sync
poweroff -f
sleep 5
EOF
chmod +x "$work/init.sh"

timeout_s=${NAVECU_VCAN_TIMEOUT:-900}
mem=${NAVECU_VCAN_UML_MEM:-1G}
nice_n=${NAVECU_VCAN_NICE:--10}
[[ $nice_n =~ ^-?[0-9]+$ ]] || { say "NAVECU_VCAN_NICE=$nice_n: expected an integer"; exit 2; }
if [ "$nice_n" -lt 0 ] && [ "$(id -u)" -ne 0 ]; then
    vsay "not root: UML runs at the caller's priority (NAVECU_VCAN_NICE=$nice_n ignored)"
    nice_n=0
fi
cpu=${NAVECU_VCAN_CPU:-auto}
pin=()
if [ "$cpu" = auto ]; then
    # the last CPU of this process's affinity list, e.g. "0-3,8,10-11" -> 11
    cpu=$(taskset -pc $$ 2>/dev/null | sed -n 's/.*: *//p' | tr ',' '\n' | tail -1 | sed 's/.*-//')
    [ -n "$cpu" ] || { vsay "cannot read the CPU affinity (taskset): UML not pinned"; cpu=none; }
fi
if [ "$cpu" != none ]; then
    if command -v taskset >/dev/null 2>&1; then pin=(taskset -c "$cpu")
    else vsay "no taskset (util-linux): UML not pinned"; cpu=none; fi
fi
# Debian's UML kernel (6.1) restores its guests' FPU state through a buffer of its own size,
# which a host CPU with a larger XSAVE area (AMX) refuses: UML then panics at its first
# process ("ptrace set fp regs failed, errno = 14"). tools/vcan/uml_xstate_shim.c, built
# here and preloaded into the UML kernel (not into the guest), gives it the host's size.
preload=()
shim_src="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)/uml_xstate_shim.c"
case $work in
*[[:space:]:]*)
    # the loader splits LD_PRELOAD at spaces and colons
    say "warning: no UML xstate shim: its directory $work has a space or a colon" ;;
*)
    if [ -f "$shim_src" ] && command -v cc >/dev/null 2>&1 &&
       cc -shared -fPIC -O2 -o "$work/uml_xstate_shim.so" "$shim_src" -ldl >"$work/shim_build.log" 2>&1; then
        preload=(env LD_PRELOAD="${LD_PRELOAD:+$LD_PRELOAD:}$work/uml_xstate_shim.so")
    else
        say "warning: the UML xstate shim did not build ($shim_src, cc; $work/shim_build.log): UML runs without it"
    fi ;;
esac
vsay "booting $uml (mem=$mem, nice $nice_n, cpu $cpu, timeout ${timeout_s}s, exchange dir $work)"
t0=$(date +%s.%N)
# UML's own exit status does not carry the guest's; TMPDIR for UML's memory file is the host's.
"${pin[@]}" nice -n "$nice_n" timeout -k 10 "$timeout_s" "${preload[@]}" "$uml" mem="$mem" root=/dev/root rootfstype=hostfs rootflags=/ rw \
    init="$work/init.sh" con=null con0=fd:0,fd:1 </dev/null >"$work/console.log" 2>&1 &
uml_pid=$!
wait "$uml_pid"
uml_rc=$?
uml_pid=
t1=$(date +%s.%N)

stage=$(cat "$work/stage" 2>/dev/null || echo "not started")
if [ -f "$work/t_booted" ]; then
    vsay "$(awk -v a="$t0" -v b="$(cat "$work/t_booted")" -v c="$t1" \
        'BEGIN{printf "UML boot %.2f s, whole run %.2f s", b-a, c-a}')"
fi

# CMD's output first, whatever happened afterwards.
[ -f "$work/stdout" ] && cat "$work/stdout"
[ -f "$work/stderr" ] && cat "$work/stderr" >&2

uml_failed() {
    say "UML FAILED ($*) - this is the harness, not CMD; UML kernel: $uml, exit status $uml_rc, last stage: $stage"
    [ -f "$work/setup_error" ] && say "guest setup error: $(cat "$work/setup_error")"
    say "last lines of the UML console:"
    tail -n 15 "$work/console.log" 2>/dev/null | sed 's/^/    /' >&2
    [ "${NAVECU_VCAN_KEEP:-0}" = 1 ] || say "(NAVECU_VCAN_KEEP=1 keeps $work for a closer look)"
}

if [ -f "$work/status" ]; then
    status=$(cat "$work/status")
    [[ $status =~ ^[0-9]+$ ]] || { uml_failed "unreadable status '$status'"; exit 125; }
    vsay "CMD exit status $status (inside UML)"
    exit "$status"
fi
if [ "$uml_rc" -eq 124 ] || [ "$uml_rc" -eq 137 ]; then
    uml_failed "timed out after ${timeout_s}s (NAVECU_VCAN_TIMEOUT); CMD did not finish"
    exit 124
fi
uml_failed "no exit status came back from the guest"
exit 125
