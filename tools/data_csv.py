"""The recorded drives' CSV files (data/*/README.md): a header row of column names, then
one row of numbers per line. Read strictly, so that a corrupt file is refused with its
file and line instead of a traceback, or of a NaN that numpy's genfromtxt would put in
place of a bad cell and the converters would turn into wrong frames or a later crash.

    read_csv(path, columns)  the file as a numpy structured array of floats, one field per
                             header column (what np.genfromtxt(names=True) gives for a good
                             file), or DataError
"""
from __future__ import annotations

import csv
import math
import warnings
from pathlib import Path
from typing import Iterable

import numpy as np


class DataError(ValueError):
    """A data file that cannot be used as it is: the message names the file, and the line
    and column where it can."""


def _first_bad_line(path: Path, names: list) -> str:
    """Where and why the rows of path do not load: 'line N: ...' (the file's own line
    numbers, the header is line 1). Run only once numpy has refused the file or found a
    value that is not finite: numpy's own messages count rows differently for different
    errors and say nothing of a NaN."""
    with open(path, encoding="utf-8", newline="") as fh:
        reader = csv.reader(fh)
        next(reader, None)
        for row in reader:
            line = reader.line_num
            if not row:
                continue
            if len(row) != len(names):
                return (f"line {line}: {len(row)} fields, the header has {len(names)} "
                        "(a line cut short?)")
            for name, cell in zip(names, row):
                try:
                    x = float(cell)
                except ValueError:
                    return f"line {line}: {name} = {cell.strip()!r} is not a number"
                if not math.isfinite(x):
                    return f"line {line}: {name} = {cell.strip()} is not finite"
    return "a row numpy could not read"


def read_csv(path, columns: Iterable[str] = ()) -> np.ndarray:
    """path as a structured array of floats named by its header (1-D, one element per row).
    DataError if the file is missing or unreadable, not UTF-8, has no header or lacks one
    of `columns`, has no row, a row with another number of fields, a cell that is not a
    number, or one that is NaN or infinite."""
    p = Path(path)
    try:
        with open(p, encoding="utf-8") as fh:
            header = fh.readline()
            names = [n.strip() for n in header.strip().split(",")] if header.strip() else []
            if not names:
                raise DataError(f"{p}: empty, no header row")
            missing = [c for c in columns if c not in names]
            if missing:
                raise DataError(f"{p}: no column {', '.join(missing)} in its header "
                                f"({', '.join(names)})")
            if len(set(names)) != len(names):
                raise DataError(f"{p}: a column name appears twice in the header")
            try:
                with warnings.catch_warnings():   # no data row: said below
                    warnings.simplefilter("ignore", UserWarning)
                    rows = np.loadtxt(fh, delimiter=",", dtype=float, ndmin=2)
                bad = bool(rows.size) and (rows.shape[1] != len(names)
                                           or not np.all(np.isfinite(rows)))
            except UnicodeDecodeError:
                raise
            except ValueError:
                bad = True
    except OSError as e:
        raise DataError(f"{p}: {e.strerror or e}") from None
    except UnicodeDecodeError:
        data = p.read_bytes()
        try:
            data.decode("utf-8")
            where = ""
        except UnicodeDecodeError as e:
            line = data.count(b"\n", 0, e.start) + 1
            where = f" (line {line}: byte 0x{data[e.start]:02X})"
        raise DataError(f"{p}: not UTF-8 text{where}") from None
    if bad:
        raise DataError(f"{p}: {_first_bad_line(p, names)}")
    if rows.shape[0] == 0:
        raise DataError(f"{p}: no data row")
    out = np.empty(rows.shape[0], dtype=[(n, float) for n in names])
    for i, n in enumerate(names):
        out[n] = rows[:, i]
    return out
