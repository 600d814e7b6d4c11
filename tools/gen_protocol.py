#!/usr/bin/env python3
"""Generate firmware/can/gen/navecu_protocol.h from the DBC: the protocol facts the
application uses beside the codec, so that each is defined once, in the DBC.

    python -m tools.gen_protocol [OUT.h]     (default firmware/can/gen/navecu_protocol.h)

It writes
- the NAV_Status HealthFlags bits, from the DBC's global value table HealthFlagBits:
  NAVECU_HEALTH_<NAME> (value 2^k, description "NAME: meaning");
- the NAV_Status pages, from the multiplexer: NAVECU_NAV_STATUS_PAGE_STATE (the page with
  Mode and HealthFlags) and the first and last counter page;
- navecu's messages as an index (NAVECU_MSG_<NAME>, NAVECU_MSG_N), their stock CAN
  identifiers (NAVECU_MSG_STOCK_IDS, the DBC's) and which of them navecu receives
  (NAVECU_MSG_IS_INPUT: sent by another node) - the identifiers an integrator may change
  (app_config_t.can_ids);
- every signal's physical range [min|max] (NAVECU_<MESSAGE>_<SIGNAL>_MIN/_MAX, float) and
  the largest raw value of every unsigned signal (..._RAW_MAX).
Names follow cantools' C generator (camel_to_snake_case), so they sit beside the codec's.
Python reads the same facts from the DBC with navecu_can.health_flag_bits().
"""
from __future__ import annotations

import sys
from pathlib import Path

import cantools
from cantools.database.can.c_source import camel_to_snake_case

ROOT = Path(__file__).resolve().parent.parent
DBC = ROOT / "firmware" / "can" / "navecu.dbc"
OUT = ROOT / "firmware" / "can" / "gen" / "navecu_protocol.h"
FLAG_TABLE = "HealthFlagBits"


def flag_bits(db) -> list[tuple[int, str, str]]:
    """(value, NAME, meaning) of each HealthFlags bit, lowest first."""
    rows = []
    for value, text in db.dbc.value_tables[FLAG_TABLE].items():
        text = str(text)
        name, _, meaning = text.partition(":")
        if value <= 0 or value & (value - 1) or not name.isidentifier() or not meaning:
            raise ValueError(f"{FLAG_TABLE}: {value} {text!r} is not 'NAME: meaning' of a bit")
        rows.append((int(value), name.strip(), meaning.strip()))
    return sorted(rows)


def c_float(x: float) -> str:
    return f"((float)({x!r}))"


def generate(db) -> str:
    out = ["/* GENERATED FILE - DO NOT EDIT. Source: firmware/can/navecu.dbc.",
           " * Regenerate with 'make codec' (tools/gen_protocol.py); 'make test' fails if stale. */",
           "#ifndef NAVECU_PROTOCOL_H", "#define NAVECU_PROTOCOL_H", "",
           f"/* NAV_Status HealthFlags bits (value table {FLAG_TABLE}) */"]
    for value, name, meaning in flag_bits(db):
        out.append(f"#define NAVECU_HEALTH_{name} 0x{value:04X}u /* {meaning} */")
    status = db.get_message_by_name("NAV_Status")
    mux = next(s for s in status.signals if s.is_multiplexer)
    pages = sorted({i for s in status.signals for i in (s.multiplexer_ids or [])})
    state = next(i for s in status.signals if s.name == "HealthFlags"
                 for i in s.multiplexer_ids)
    counters = [p for p in pages if p != state]
    if counters != list(range(counters[0], counters[-1] + 1)):
        raise ValueError("NAV_Status: the counter pages are not consecutive")
    names = [camel_to_snake_case(m.name).upper() for m in db.messages]
    out += ["", "/* navecu's messages: index, stock identifier, direction */",
            "typedef enum {"]
    out += [f"    NAVECU_MSG_{n} = {i}," for i, n in enumerate(names)]
    out += [f"    NAVECU_MSG_N = {len(names)}", "} navecu_msg_t;",
            "#define NAVECU_MSG_STOCK_IDS {" + ", ".join(f"0x{m.frame_id:03X}u" for m in db.messages) + "}",
            "#define NAVECU_MSG_IS_INPUT {" + ", ".join("0u" if "NAVECU" in m.senders else "1u"
                                                        for m in db.messages) + "}"]
    out += ["", f"/* NAV_Status pages ({mux.name}) */",
            f"#define NAVECU_NAV_STATUS_PAGE_STATE {state}u",
            f"#define NAVECU_NAV_STATUS_PAGE_COUNTERS_FIRST {counters[0]}u",
            f"#define NAVECU_NAV_STATUS_PAGE_COUNTERS_LAST {counters[-1]}u", "",
            "/* signal ranges: physical [min, max] as in the DBC; raw maximum of unsigned ones */"]
    for msg in db.messages:
        for sig in msg.signals:
            base = f"NAVECU_{camel_to_snake_case(msg.name)}_{camel_to_snake_case(sig.name)}".upper()
            if sig.minimum is not None and sig.maximum is not None:
                out.append(f"#define {base}_MIN {c_float(float(sig.minimum))}")
                out.append(f"#define {base}_MAX {c_float(float(sig.maximum))}")
            if not sig.is_signed:
                out.append(f"#define {base}_RAW_MAX {(1 << sig.length) - 1}u")
    out += ["", "#endif", ""]
    return "\n".join(out)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0]) if argv else OUT
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(generate(cantools.database.load_file(str(DBC))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
