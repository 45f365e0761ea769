"""gdb script (run by run.sh): the executed instructions of one call of the unrolled
kernel's AVX2 instance, one program counter per line, into $TRACE_OUT.

It stops at every one-run instance of `UnrolledAba::run_avx2`, lets the scene's first
calls go (SKIP, default 20) and the next, then single-steps one call from its first
instruction, libm's `sincos` calls included, until it returns to the caller.
"""

import os

import gdb

gdb.execute("set pagination off")
gdb.execute("set confirm off")
gdb.execute("set environment SATSIM_INSTRUCTIONS=avx2")
# One run's instances (`run_avx2<f64, N, EXACT, LOADED>`): the scene calls one of them.
gdb.execute("rbreak ^run_avx2<f64, ", to_string=True)
gdb.execute("run " + os.environ["SATSIM_ARGS"] + " > /dev/null", to_string=True)
for _ in range(int(os.environ.get("SKIP", "20"))):
    gdb.execute("continue", to_string=True)
# The breakpoints sit after the prologue: break again at the function's first instruction
# (`info symbol`: its name + the offset of this one), where `$sp` is what it is at `ret`.
pc = int(gdb.parse_and_eval("$pc"))
where = gdb.execute("info symbol $pc", to_string=True).split(" in section")[0]
offset = int(where.rsplit("+", 1)[1]) if "+" in where else 0
gdb.execute("delete")
gdb.execute(f"break *{pc - offset:#x}", to_string=True)
gdb.execute("continue", to_string=True)
gdb.execute("delete")
sp0 = int(gdb.parse_and_eval("$sp"))
with open(os.environ["TRACE_OUT"], "w") as out:
    for _ in range(100_000):
        pc = int(gdb.parse_and_eval("$pc"))
        out.write(f"{pc:x}\n")
        insn = gdb.execute("x/i $pc", to_string=True).split(":", 1)[-1].split()
        returning = insn[:1] == ["ret"] and int(gdb.parse_and_eval("$sp")) == sp0
        gdb.execute("stepi", to_string=True)
        if returning:
            break
gdb.execute("kill")
