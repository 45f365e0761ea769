#!/usr/bin/env bash
# One call of the unrolled kernel, as the core runs it: the executed instructions of the
# AVX2 instance (one run, the peer orbit's scene, its 22nd call) traced with gdb and fed to
# llvm-mca, a model of the core's pipeline (Zen 3's: the newest in LLVM 14). Not run by CI.
# Needs gdb, objdump and llvm-mca (Debian: gdb, binutils, llvm). Usage, from the repository
# root: bash benches/kernel_trace/run.sh [SCENE]
# Prints llvm-mca's summary, its dispatch stalls and the longest dependency chain
# (critical_path.py); the trace stays in $OUT (default
# /tmp/kernel_trace) for other views: llvm-mca -mcpu=znver3 -timeline $OUT/trace.s
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
SCENE="$(realpath "${1:-benches/peers/orbit.toml}")"
OUT="${OUT:-/tmp/kernel_trace}"
mkdir -p "$OUT"
# The release profile with line tables (source lines beside the instructions).
CARGO_TARGET_DIR="$OUT/target" CARGO_PROFILE_RELEASE_DEBUG=line-tables-only \
  cargo build --release -p satsim-cli
BIN="$OUT/target/release/satsim"
SATSIM_ARGS="run $SCENE --out $OUT/run" TRACE_OUT="$OUT/trace.txt" \
  gdb -q -batch -x "$HERE/trace.py" "$BIN" > "$OUT/gdb.log" 2>&1
# gdb runs the position-independent binary at this base (address randomisation off).
python3 "$HERE/mca_input.py" "$BIN" "$OUT/trace.txt" 0x555555554000 "$OUT/trace.s" "$OUT/trace.src"
llvm-mca -mcpu=znver3 --iterations=1 -dispatch-stats "$OUT/trace.s" > "$OUT/mca.txt"
sed -n '1,9p' "$OUT/mca.txt"
grep -A4 'Dynamic Dispatch Stall Cycles' "$OUT/mca.txt"
python3 "$HERE/critical_path.py" "$OUT/mca.txt"
