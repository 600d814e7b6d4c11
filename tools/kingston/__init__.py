"""The recorded Kingston 2008 drive (real IMU, OBD speed, GNSS, SPAN reference) through
the firmware: convert.py (CSV -> candump log through the DBC), run.py (convert, run
build/host/navecu, compare with the reference), analyse.py (facts about the data).
docs/kingston.md describes the data, the conversion and the measured results."""
