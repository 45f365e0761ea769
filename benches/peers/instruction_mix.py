"""What the instructions of a run are: floating-point arithmetic (and its flops), moves and
shuffles of floating-point registers, integer and branch work, per right-hand side and per
function. Not run by cargo or CI (like the rest of benches/peers).

    valgrind --tool=callgrind --dump-instr=yes --compress-pos=no --compress-strings=no \
        --callgrind-out-file=cg.out target/release/satsim run orbit600.toml --out /tmp/o
    python3 benches/peers/instruction_mix.py cg.out 24000     # 24 000 right-hand sides

Callgrind counts every executed instruction at its address; objdump names the instruction
at each address. Flops: a scalar add, subtract, multiply, divide, square root, min or max is
one, a two-wide packed one two (four for 256-bit registers), a fused multiply-add twice that.
"""

import collections
import re
import subprocess
import sys

ARITH = r"(add|sub|mul|div|sqrt|min|max)"
MOVES = (
    r"(mov(sd|apd|upd|hpd|lpd|ddup|q|aps|ups)|unpck[lh]p[sd]|shufp[sd]|movlhps|movhlps"
    r"|blendpd|permilpd|perm2f128|insertf128|extractf128|broadcastsd)$"
)


def classify(op, args):
    """(class, flops) of one instruction."""
    o = op[1:] if op.startswith("v") else op
    wide = 2 if "ymm" in args else 1
    if re.match(ARITH + r"sd$", o):
        return "fp arithmetic, scalar", 1
    if re.match(ARITH + r"pd$", o):
        return "fp arithmetic, packed", 2 * wide
    if re.match(r"fn?m(add|sub)\d+sd$", o):
        return "fp arithmetic, scalar", 2
    if re.match(r"fn?m(add|sub)\d+pd$", o):
        return "fp arithmetic, packed", 4 * wide
    if re.match(MOVES, o):
        return "fp moves and shuffles", 0
    if re.match(r"(and|andn|or|xor)p[sd]$", o):
        return "fp sign and masks", 0
    if re.match(r"(u?comisd|cmp\w*[sp]d|cvt\w+)$", o):
        return "fp compares and conversions", 0
    if o.startswith(("j", "cmov", "set")) or o in ("call", "ret", "cmp", "test"):
        return "branches and compares", 0
    if o.startswith("mov") or o in ("push", "pop", "lea"):
        return "integer moves and addresses", 0
    return "other", 0


def main():
    path, per = sys.argv[1], int(sys.argv[2])
    counts = collections.defaultdict(collections.Counter)  # object -> address -> count
    where = {}
    obj = fn = None
    skip = False
    for line in open(path):
        if line.startswith("ob="):
            obj = line[3:].strip()
        elif line.startswith("fn="):
            fn = line[3:].strip()
        elif line.startswith("calls="):
            skip = True  # the next line is the call's inclusive cost, not an instruction's
        elif line.startswith("0x"):
            if skip:
                skip = False
                continue
            a, _, n = line.split()[:3]
            counts[obj][int(a, 16)] += int(n)
            where[(obj, int(a, 16))] = fn
    classes, funcs = collections.Counter(), collections.defaultdict(collections.Counter)
    flops = 0
    for obj, by_addr in counts.items():
        dump = subprocess.run(
            ["objdump", "-d", "--no-show-raw-insn", obj], capture_output=True, text=True
        ).stdout
        ops = {}
        for l in dump.splitlines():
            m = re.match(r"\s*([0-9a-f]+):\s+(\S+)\s*(.*)", l)
            if m:
                ops[int(m.group(1), 16)] = (m.group(2), m.group(3))
        for a, n in by_addr.items():
            c, f = classify(*ops.get(a, ("?", "")))
            classes[c] += n
            flops += n * f
            funcs[where[(obj, a)]]["ir"] += n
            funcs[where[(obj, a)]]["flops"] += n * f
    total = sum(classes.values())
    print(f"{total / per:.0f} instructions and {flops / per:.0f} flops per right-hand side")
    for c, n in classes.most_common():
        print(f"  {c:30s} {n / per:7.0f}  {100 * n / total:5.1f} %")
    print("functions: instructions, flops per right-hand side")
    for f, c in sorted(funcs.items(), key=lambda kv: -kv[1]["ir"])[:20]:
        print(f"  {c['ir'] / per:7.0f} {c['flops'] / per:7.0f}  {f[:90]}")


if __name__ == "__main__":
    main()
