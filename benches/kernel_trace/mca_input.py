"""The trace of trace.py as llvm-mca input: each program counter's instruction (objdump,
AT&T syntax), without jumps, calls and returns (taken as predicted), with its source line
beside it in a second file. Usage: mca_input.py BINARY TRACE LOAD_BASE OUT.s OUT.src
"""

import os
import re
import subprocess
import sys

binary, trace, base, out_s, out_src = sys.argv[1:6]
base = int(base, 16)
with open(trace) as f:
    traced = [int(line, 16) - base for line in f]
# The binary's own instructions (the kernel, libm's sincos); a shared library's (libc's
# `memcpy`, say) lie outside its address range and cannot be disassembled from it.
size = os.path.getsize(binary)
pcs = [pc for pc in traced if 0 <= pc < size]
addrs = sorted(set(pcs))
ranges, start, prev = [], addrs[0], addrs[0]
for a in addrs[1:]:
    if a - prev > 4096:
        ranges.append((start, prev))
        start = a
    prev = a
ranges.append((start, prev))
insn = {}
for lo, hi in ranges:
    dump = subprocess.run(
        [
            "objdump",
            "-d",
            "-l",
            "--no-show-raw-insn",
            "-M",
            "att",
            f"--start-address={lo}",
            f"--stop-address={hi + 16}",
            binary,
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    line = None
    for row in dump.splitlines():
        m = re.match(r"^(/\S+):(\d+)", row)
        if m:
            line = "/".join(m.group(1).split("/")[-2:]) + ":" + m.group(2)
            continue
        m = re.match(r"^\s+([0-9a-f]+):\s+(.*)$", row)
        if m:
            insn[int(m.group(1), 16)] = (m.group(2).split("#")[0].strip(), line or "?")
kept = []
for pc in pcs:
    text, line = insn[pc]
    op = text.split()[0]
    if op.startswith(("j", "call", "ret", "nop", "endbr")) or op in ("cs", "data16"):
        continue
    kept.append((re.sub(r"<[^>]*>", "", text).strip(), line))
with open(out_s, "w") as f:
    f.write("\n".join(t for t, _ in kept) + "\n")
with open(out_src, "w") as f:
    f.write("\n".join(l for _, l in kept) + "\n")
outside = len(traced) - len(pcs)
print(
    f"{len(traced)} instructions traced, {len(kept)} to llvm-mca"
    + (f" ({outside} in shared libraries left out)" if outside else "")
)
