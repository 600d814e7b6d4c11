"""The comma2k19 RAV4 segment (data/comma2k19-rav4): a real car's whole bus with navecu."""
