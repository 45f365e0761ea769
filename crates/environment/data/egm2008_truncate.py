"""Truncates brahe's EGM2008 coefficient file (ICGEM .gfc, fully normalised, tide-free, to
degree 120) to degree and order 70: the header and every `gfc` line with L <= 70, unchanged.

Source: the `brahe` package's source distribution on PyPI, version 1.8.0
(brahe-1.8.0.tar.gz, sha256 64648f8c755b235305d6e9e499414fe1658202900a34c090793ab60682c849c9),
file brahe-1.8.0/data/gravity_models/EGM2008_120.gfc.

Run: pip download brahe==1.8.0 --no-deps --no-binary :all: -d .   # fetches brahe-1.8.0.tar.gz
     tar xzf brahe-1.8.0.tar.gz brahe-1.8.0/data/gravity_models/EGM2008_120.gfc
     python3 egm2008_truncate.py brahe-1.8.0/data/gravity_models/EGM2008_120.gfc > egm2008_70.gfc
"""
import sys

MAX_DEGREE = 70

lines = open(sys.argv[1], encoding="ascii").read().splitlines()
out = []
in_header = True
for line in lines:
    if in_header:
        if line.startswith("max_degree"):
            line = f"max_degree                  {MAX_DEGREE}"
        out.append(line.rstrip())
        if line.startswith("end_of_head"):
            in_header = False
        continue
    fields = line.split()
    if not fields:
        continue
    assert fields[0] == "gfc", line
    if int(fields[1]) <= MAX_DEGREE:
        out.append(line.rstrip())
print("\n".join(out))
