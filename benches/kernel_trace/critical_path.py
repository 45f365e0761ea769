"""The longest chain of dependent instructions in llvm-mca's input, with llvm-mca's own
latencies (its "Instruction Info" table): a lower bound on the cycles of one call that no
ordering of the instructions beats. Usage: critical_path.py MCA_OUTPUT (run.sh's mca.txt).

Dependencies through registers (xmm/ymm/zmm as one register, a general register's 32-,
16- and 8-bit names as the 64-bit one, the flags) and through memory operands written the
same way (a stack slot, a field at the same base register). An approximation: llvm-mca's
own simulation (run.sh) ignores memory dependencies.
"""

import re
import sys

with open(sys.argv[1]) as f:
    lines = f.read().splitlines()
head = next(i for i, l in enumerate(lines) if l.startswith("[1]    [2]"))
table = []
for l in lines[head + 1 :]:
    if not l.strip():
        break
    cols, text = l.split("\t", 1) if "\t" in l else (l, "")  # (`vzeroupper` has no operands)
    table.append((int(cols.split()[1]), cols.split()[-1], text.strip()))

GPR = {"a": "ax", "b": "bx", "c": "cx", "d": "dx", "si": "si", "di": "di", "bp": "bp", "sp": "sp"}


def reg(r):
    r = r.strip("%")
    m = re.match(r"[xyz]mm(\d+)$", r)
    if m:
        return "v" + m.group(1)
    m = re.match(r"r(\d+)[dwb]?$", r)
    if m:
        return "r" + m.group(1)
    m = re.match(r"[re]?([abcd])[xlh]$|[re]?(si|di|bp|sp)l?$", r)
    if m:
        return GPR[m.group(1) or m.group(2)]
    return r


def operands(text):
    out, depth, cur = [], 0, ""
    for ch in text:
        depth += ch == "("
        depth -= ch == ")"
        if ch == "," and depth == 0:
            out.append(cur.strip())
            cur = ""
        else:
            cur += ch
    return out + [cur.strip()] if cur.strip() else out


ready, finish, pred, who = {}, [], [], {}
for i, (lat, op, text) in enumerate(table):
    ops = operands(text)
    srcs, dsts = [], []
    if op.startswith("push"):
        srcs = [reg(o) for o in ops]
    elif op.startswith("pop"):
        dsts = [reg(o) for o in ops]
    elif ops:
        *src, dst = ops
        for o in src:
            if o.startswith("$"):
                continue
            if "(" in o:
                srcs += [reg(b) for b in re.findall(r"%\w+", o)] + ["M:" + o]
            else:
                srcs.append(reg(o))
        if "(" in dst:
            srcs += [reg(b) for b in re.findall(r"%\w+", dst)]
            dsts.append("M:" + dst)
        else:
            dsts.append(reg(dst))
            # Two-operand (legacy) forms read their destination too.
            if not op.startswith(("v", "mov", "lea", "set")):
                srcs.append(reg(dst))
        if op.startswith(("cmp", "test", "ucomi", "vucomi")):
            dsts = ["flags"]
        if op.startswith(("cmov", "set", "adc", "sbb")):
            srcs.append("flags")
        if op.startswith(("xor", "vxorp", "vpxor")) and len(set(ops[:2])) == 1:
            srcs = []  # zeroing idiom
    start, by = 0, None
    for s in srcs:
        if ready.get(s, 0) > start:
            start, by = ready[s], who[s]
    finish.append(start + lat)
    pred.append(by)
    for d in dsts:
        ready[d], who[d] = finish[i], i
end = max(finish)
chain, i = [], finish.index(end)
while i is not None:
    chain.append(i)
    i = pred[i]
print(f"critical path: {end} cycles through {len(chain)} of {len(table)} instructions")
