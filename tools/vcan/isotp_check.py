"""The firmware's ISO-TP transport against can-isotp over vcan0 (run inside with_vcan.sh).

    python -m tools.vcan.isotp_check --peer build/host/tests/isotp_peer

Starts tests/tools/isotp_peer.c (firmware/diag/isotp.c as a server: echo, or a generated
message for a request 01 HH LL) once per scenario with that scenario's options, plays the
tester with can-isotp (its own ISO-TP implementation, pure Python over python-can) or with
raw python-can frames built from ISO 15765-2's layouts where a fault has to be injected,
records every frame on the bus with a python-can listener (kernel receive timestamps), and
prints one JSON object a line: {"scenario": NAME, ...} with what happened, for
tests/python/test_isotp_peer.py to judge. Exit status 0 when every scenario ran (its
verdicts are the test's), 1 when one raised. Exits 2 with "NO VCAN" when vcan0 is missing.
"""
import argparse
import json
import subprocess
import sys
import threading
import time
import traceback

import can
import isotp

IFACE = "vcan0"
REQ_ID = 0x7A0   # the ECU's physical request ID: the tester sends here
RSP_ID = 0x7A8   # the ECU's response ID
PAD = 0xCC


def pattern(n, seed=0):
    return bytes((i * 7 + seed + (i >> 8)) & 0xFF for i in range(n))


def generated(n):
    return bytes(i % 251 for i in range(n))


class Recorder(can.Listener):
    """Every frame on the bus: (t_s, id, data bytes), kernel receive time."""

    def __init__(self):
        self.frames = []
        self.lock = threading.Lock()

    def on_message_received(self, msg):
        if msg.is_error_frame or msg.is_remote_frame:
            return
        with self.lock:
            self.frames.append((msg.timestamp, msg.arbitration_id, bytes(msg.data)))

    def mark(self):
        with self.lock:
            return len(self.frames)

    def since(self, mark):
        with self.lock:
            return list(self.frames[mark:])


class Peer:
    """isotp_peer with options; its JSON events collected by a reader thread."""

    def __init__(self, binary, *args):
        self.proc = subprocess.Popen([binary, "--can", IFACE, *map(str, args)],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.events = []
        self.cv = threading.Condition()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()
        if not self.wait_for(lambda e: e["event"] == "ready", 10.0):
            self.proc.kill()
            raise RuntimeError("isotp_peer did not start: " + self.proc.stderr.read())

    def _read(self):
        for line in self.proc.stdout:
            line = line.strip()
            if line.startswith("{"):
                with self.cv:
                    self.events.append(json.loads(line))
                    self.cv.notify_all()

    def wait_for(self, pred, timeout):
        end = time.monotonic() + timeout
        with self.cv:
            while True:
                for e in self.events:
                    if pred(e):
                        return e
                left = end - time.monotonic()
                if left <= 0:
                    return None
                self.cv.wait(left)

    def count(self, name):
        """the last value of counter name (0 if it never moved)"""
        with self.cv:
            vals = [e["value"] for e in self.events if e["event"] == "count" and e["name"] == name]
        return vals[-1] if vals else 0

    def stop(self):
        self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.reader.join(timeout=5)
        summary = next((e for e in self.events if e["event"] == "summary"), None)
        return summary


class Tester:
    """can-isotp on its own python-can socket, errors collected."""

    def __init__(self, **params):
        self.bus = can.Bus(interface="socketcan", channel=IFACE,
                           can_filters=[{"can_id": RSP_ID, "can_mask": 0x7FF, "extended": False}])
        self.errors = []
        addr = isotp.Address(isotp.AddressingMode.Normal_11bits, txid=REQ_ID, rxid=RSP_ID)
        p = {"blocking_send": False}
        p.update(params)
        self.stack = isotp.CanStack(self.bus, address=addr, params=p,
                                    error_handler=lambda e: self.errors.append(type(e).__name__))
        self.stack.start()

    def exchange(self, data, timeout=20.0):
        self.stack.send(data)
        return self.stack.recv(block=True, timeout=timeout)

    def close(self):
        self.stack.stop()
        self.bus.shutdown()


class Raw:
    """Hand-made frames (ISO 15765-2 layouts) on their own socket; ECU frames read back."""

    def __init__(self):
        self.bus = can.Bus(interface="socketcan", channel=IFACE,
                           can_filters=[{"can_id": RSP_ID, "can_mask": 0x7FF, "extended": False}])

    def send(self, *data):
        self.bus.send(can.Message(arbitration_id=REQ_ID, is_extended_id=False, data=bytes(data)))

    def recv(self, timeout=2.0):
        m = self.bus.recv(timeout)
        return None if m is None else (m.timestamp, bytes(m.data))

    def close(self):
        self.bus.shutdown()


# ---------------------------------------------------------------- frame analysis

def kind(data):
    return data[0] >> 4 if data else None


def ecu_frames(frames):
    return [(t, d) for t, i, d in frames if i == RSP_ID]


def tester_frames(frames):
    return [(t, d) for t, i, d in frames if i == REQ_ID]


def padding_ok(frames):
    """every ECU frame DLC 8 and its unused bytes 0xCC"""
    bad = []
    for _, d in ecu_frames(frames):
        used = {0: 1 + (d[0] & 0x0F), 1: 8, 3: 3}.get(kind(d))
        if kind(d) == 2:
            used = 8  # a CF's used length depends on the message; checked by the caller
        if len(d) != 8 or (used is not None and any(b != PAD for b in d[used:])):
            bad.append(d.hex())
    return bad


def cf_gaps_ms(frames, sender_id):
    """gaps between consecutive CFs of sender_id that no FC separates, in ms"""
    gaps, last = [], None
    for t, i, d in frames:
        if kind(d) == 3 and i != sender_id:
            last = None  # a new block: the first CF may follow the FC at once
        elif i == sender_id and kind(d) == 2:
            if last is not None:
                gaps.append((t - last) * 1000.0)
            last = t
        elif i == sender_id and kind(d) == 1:
            last = None
    return gaps


def cf_shortfall_ms(frames, sender_id, st_min_ms):
    """the most by which a CF of sender_id came earlier than k x STmin after the first CF of
    its block (k its place in the block), in ms; 0 when none did. Cumulative, so that the
    delay between a sender's clock read and the kernel's timestamp of one frame, which
    shortens one gap and lengthens the next, does not count twice"""
    worst, first, k = 0.0, None, 0
    for t, i, d in frames:
        if (kind(d) == 3 and i != sender_id) or (i == sender_id and kind(d) == 1):
            first = None
        elif i == sender_id and kind(d) == 2:
            if first is None:
                first, k = t, 0
            else:
                k += 1
                worst = max(worst, k * st_min_ms - (t - first) * 1000.0)
    return round(worst, 3)


def cfs_per_block(frames, sender_id):
    """CFs of sender_id between two FCs of the other side"""
    blocks, n = [], None
    for _, i, d in frames:
        if i != sender_id and kind(d) == 3:
            if n is not None:
                blocks.append(n)
            n = 0
        elif i == sender_id and kind(d) == 2 and n is not None:
            n += 1
    if n is not None:
        blocks.append(n)
    return blocks


def stats(gaps):
    if not gaps:
        return {"n": 0}
    s = sorted(gaps)
    return {"n": len(s), "min_ms": round(s[0], 3), "median_ms": round(s[len(s) // 2], 3),
            "max_ms": round(s[-1], 3), "sum_ms": round(sum(s), 3)}


# ---------------------------------------------------------------- scenarios

def sc_echo(peer_bin, rec):
    """default ECU (BS 8, STmin 0, padded 0xCC); can-isotp unpadded: 1..4095 bytes both ways"""
    peer = Peer(peer_bin)
    tester = Tester()
    mark = rec.mark()
    sizes = [1, 2, 7, 8, 62, 300, 4095]
    ok = {}
    for n in sizes:
        data = pattern(n, n)
        ok[n] = tester.exchange(data) == data
    tester.close()
    frames = rec.since(mark)
    summary = peer.stop()
    fcs = [d for _, d in ecu_frames(frames) if kind(d) == 3]
    short = sum(1 for _, d in tester_frames(frames) if len(d) < 8)
    return {"echo_ok": ok, "tester_errors": tester.errors, "padding_bad": padding_ok(frames),
            "ecu_fc": sorted({d[:3].hex() for d in fcs}), "ecu_fc_count": len(fcs),
            "tester_short_frames": short, "ecu_blocks": cfs_per_block(frames, REQ_ID),
            "summary": summary}


def sc_ecu_flow_control(peer_bin, rec):
    """the ECU announces BS 4 / STmin 5 ms, then BS 0 / STmin 0xF5 (500 us): can-isotp obeys"""
    out = {}
    for name, bs, st, n in (("ms", 4, 5, 200), ("us", 0, 0xF5, 300)):
        peer = Peer(peer_bin, "--bs", bs, "--stmin", st)
        tester = Tester()
        mark = rec.mark()
        data = pattern(n, 3)
        ok = tester.exchange(data) == data
        tester.close()
        frames = rec.since(mark)
        # the request only: the frames up to the tester's last CF of it
        req = [f for f in frames if f[1] == REQ_ID or kind(f[2]) == 3]
        summary = peer.stop()
        out[name] = {"ok": ok, "errors": tester.errors,
                     "ecu_fc": sorted({d[:3].hex() for _, i, d in req if i == RSP_ID}),
                     "blocks": cfs_per_block(req, REQ_ID), "gaps": stats(cf_gaps_ms(req, REQ_ID)),
                     "summary": summary}
    return out


def sc_tester_flow_control(peer_bin, rec):
    """can-isotp announces BS 3 / STmin 10 ms, then BS 0 / STmin 0xF5, then BS 1 / 0: the ECU
    obeys when sending its (generated) responses"""
    out = {}
    for name, bs, st, n in (("ms", 3, 10, 200), ("us", 0, 0xF5, 300), ("bs1", 1, 0, 100)):
        peer = Peer(peer_bin)
        tester = Tester(blocksize=bs, stmin=st)
        mark = rec.mark()
        got = tester.exchange(bytes([0x01, n >> 8, n & 0xFF]))
        tester.close()
        frames = rec.since(mark)
        summary = peer.stop()
        st_ms = st if st <= 0x7F else (st - 0xF0) / 10.0
        out[name] = {"ok": got == generated(n), "errors": tester.errors,
                     "tester_fc": sorted({d[:3].hex() for _, d in tester_frames(frames) if kind(d) == 3}),
                     "blocks": cfs_per_block(frames, RSP_ID), "gaps": stats(cf_gaps_ms(frames, RSP_ID)),
                     "shortfall_ms": cf_shortfall_ms(frames, RSP_ID, st_ms), "summary": summary}
    return out


def sc_generate_max(peer_bin, rec):
    """the longest response, 4095 bytes, to can-isotp's defaults (BS 8, STmin 0)"""
    peer = Peer(peer_bin)
    tester = Tester()
    mark = rec.mark()
    got = tester.exchange(bytes([0x01, 0x0F, 0xFF]))
    tester.close()
    frames = rec.since(mark)
    summary = peer.stop()
    return {"ok": got == generated(4095), "errors": tester.errors,
            "ecu_cfs": sum(1 for _, d in ecu_frames(frames) if kind(d) == 2),
            "padding_bad": padding_ok(frames), "summary": summary}


def sc_unpadded(peer_bin, rec):
    """the ECU with padding off: shortest DLCs, which can-isotp accepts"""
    peer = Peer(peer_bin, "--no-padding")
    tester = Tester()
    mark = rec.mark()
    ok = {n: tester.exchange(pattern(n, 1)) == pattern(n, 1) for n in (2, 17)}
    tester.close()
    frames = rec.since(mark)
    summary = peer.stop()
    return {"ok": ok, "errors": tester.errors,
            "ecu_dlcs": [(d[0] >> 4, len(d)) for _, d in ecu_frames(frames)], "summary": summary}


def sc_wait(peer_bin, rec):
    """the server holds each message 300 ms: a second request meets FC WAITs, then CTS"""
    peer = Peer(peer_bin, "--hold-ms", 300)
    tester = Tester(wftmax=10)
    mark = rec.mark()
    a, b = pattern(50, 1), pattern(60, 2)
    tester.stack.send(a)
    tester.stack.send(b)
    ra = tester.stack.recv(block=True, timeout=10)
    rb = tester.stack.recv(block=True, timeout=10)
    tester.close()
    frames = rec.since(mark)
    summary = peer.stop()
    ecu_fc = [d[:3].hex() for _, d in ecu_frames(frames) if kind(d) == 3]
    return {"ok": [ra == a, rb == b], "errors": tester.errors, "ecu_fc": ecu_fc,
            "summary": summary}


def sc_overflow(peer_bin, rec):
    """5000 bytes (an escape-sequence FF): the ECU answers FC OVFLW, can-isotp reports it"""
    peer = Peer(peer_bin)
    tester = Tester(max_frame_size=5000)
    mark = rec.mark()
    tester.stack.send(pattern(5000))
    time.sleep(0.5)
    after = tester.exchange(pattern(20))  # the channel works on
    tester.close()
    frames = rec.since(mark)
    summary = peer.stop()
    return {"errors": tester.errors, "ecu_fc": [d[:3].hex() for _, d in ecu_frames(frames) if kind(d) == 3],
            "tester_ff": [d[:6].hex() for _, d in tester_frames(frames) if kind(d) == 1],
            "after_ok": after == pattern(20), "summary": summary}


def sc_timeout_cr(peer_bin, rec):
    """raw FF, the ECU's FC, then silence: N_Cr (1000 ms) drops the message"""
    peer = Peer(peer_bin)
    raw = Raw()
    raw.send(0x10, 20, 1, 2, 3, 4, 5, 6)
    fc = raw.recv()
    ev = peer.wait_for(lambda e: e.get("name") == "rx_timeout_cr", 5.0)
    time.sleep(0.1)
    late = raw.recv(timeout=0.2)
    raw.close()
    summary = peer.stop()
    return {"fc": fc[1].hex() if fc else None,
            "after_fc_s": (ev["t_us"] / 1e6 - fc[0]) if (ev and fc) else None,
            "ecu_after": late[1].hex() if late else None, "summary": summary}


def sc_timeout_bs(peer_bin, rec):
    """the ECU's FF unanswered: N_Bs (1000 ms) aborts its transmission"""
    peer = Peer(peer_bin)
    raw = Raw()
    raw.send(0x03, 0x01, 0x00, 100)
    ff = raw.recv()
    ev = peer.wait_for(lambda e: e.get("name") == "tx_timeout_bs", 5.0)
    late = raw.recv(timeout=0.2)
    raw.close()
    summary = peer.stop()
    return {"ff": ff[1].hex() if ff else None,
            "after_ff_s": (ev["t_us"] / 1e6 - ff[0]) if (ev and ff) else None,
            "ecu_after": late[1].hex() if late else None, "summary": summary}


def sc_lost_cf(peer_bin, rec):
    """raw FF, CF 1, CF 3 (CF 2 lost): the ECU drops the message and reports a wrong SN;
    the next message from can-isotp goes through"""
    peer = Peer(peer_bin)
    raw = Raw()
    data = pattern(30, 9)
    raw.send(0x10, 30, *data[0:6])
    fc = raw.recv()
    raw.send(0x21, *data[6:13])
    raw.send(0x23, *data[20:27])
    raw.send(0x24, *data[27:30])
    ev = peer.wait_for(lambda e: e.get("name") == "rx_wrong_sn", 3.0)
    echo = raw.recv(timeout=0.3)  # nothing: the message was dropped
    raw.close()
    tester = Tester()
    again = tester.exchange(data)
    tester.close()
    summary = peer.stop()
    rx = [e for e in peer.events if e["event"] == "rx"]
    return {"fc": fc[1].hex() if fc else None, "reported": ev is not None,
            "ecu_after": echo[1].hex() if echo else None, "again_ok": again == data,
            "rx_lens": [e["len"] for e in rx], "summary": summary}


def sc_reserved_st_min(peer_bin, rec):
    """a raw FC with the reserved STmin 0x80: the ECU spaces its CFs 127 ms"""
    peer = Peer(peer_bin)
    raw = Raw()
    raw.send(0x03, 0x01, 0x00, 30)
    ff = raw.recv()
    raw.send(0x30, 0x00, 0x80)
    cfs = [raw.recv() for _ in range(4)]
    raw.close()
    summary = peer.stop()
    ts = [c[0] for c in cfs if c]
    return {"ff": ff[1].hex() if ff else None, "cfs": [c[1].hex() for c in cfs if c],
            "gaps_ms": [round((b - a) * 1000.0, 3) for a, b in zip(ts, ts[1:])], "summary": summary}


SCENARIOS = [sc_echo, sc_ecu_flow_control, sc_tester_flow_control, sc_generate_max, sc_unpadded,
             sc_wait, sc_overflow, sc_timeout_cr, sc_timeout_bs, sc_lost_cf, sc_reserved_st_min]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--peer", required=True, help="the isotp_peer executable")
    ap.add_argument("--only", action="append", default=[], help="run only these scenarios")
    a = ap.parse_args()
    try:
        bus = can.Bus(interface="socketcan", channel=IFACE)
    except OSError as e:
        print(f"NO VCAN: cannot open {IFACE}: {e}", file=sys.stderr)
        return 2
    rec = Recorder()
    notifier = can.Notifier(bus, [rec], timeout=0.05)
    failed = 0
    for sc in SCENARIOS:
        name = sc.__name__[3:]
        if a.only and name not in a.only:
            continue
        t0 = time.monotonic()
        try:
            r = sc(a.peer, rec)
        except Exception:  # noqa: BLE001 - reported to the test as the scenario's result
            r = {"exception": traceback.format_exc()}
            failed = 1
        r["scenario"] = name
        r["seconds"] = round(time.monotonic() - t0, 2)
        print(json.dumps(r), flush=True)
    notifier.stop()
    bus.shutdown()
    return failed


if __name__ == "__main__":
    sys.exit(main())
