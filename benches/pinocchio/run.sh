#!/usr/bin/env bash
# Side-by-side benchmark of satsim and Pinocchio 4.1 (C++) on the same models, in ONE run.
# Not part of the build or of CI (results: docs/src/results/performance.md; details:
# docs/src/engineering/performance-decisions.md and algorithms.md).
#
#   bash benches/pinocchio/run.sh                      # the satellite, 5 interleaved rounds
#   MODELS="satellite chain10 binary10 chain100 binary100" ROUNDS=7 bash benches/pinocchio/run.sh
#   (chain1000 and binary1000 are exported too, but Pinocchio 4.1's Data for 1000 joints was
#   killed for lack of memory on a 24 GiB machine: its rows then read "failed")
#   NATIVE=1 bash benches/pinocchio/run.sh             # both sides for the build machine's CPU
#   ALIGNED=1 bash benches/pinocchio/run.sh            # Pinocchio with RevoluteX/Y/Z joints
#
# Needs: `pip install pin==4.1.0` (Pinocchio, boost as cmeel packages), Eigen 3.4 headers
# (`apt-get install libeigen3-dev`, or `pip install cmeel-eigen`), g++, cargo.
#
# Steps: builds `satsim` (cargo, release profile) and harness.cpp (g++); exports the models
# (export_models.py: satellite, chains and binary trees of 10/100/1000 bodies) and checks
# that Pinocchio and `satsim dynamics` agree on them; then, for each model, alternates
# `satsim bench` and the Pinocchio harness ROUNDS times with the same number of calls per
# repetition, and prints the median over rounds of each figure and the ratio.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
MODELS="${MODELS:-satellite}"
ROUNDS="${ROUNDS:-5}"
OUT="${OUT:-$ROOT/target/pinocchio-bench}"
CXX="${CXX:-g++}"
CXXFLAGS="${CXXFLAGS:--O3 -DNDEBUG}"
mkdir -p "$OUT"

PREFIX="$(python3 -c 'import cmeel, os; print(os.path.join(os.path.dirname(cmeel.__path__[0]), "cmeel.prefix"))')"
[ -f "$PREFIX/include/pinocchio/config.hpp" ] || { echo "no Pinocchio headers under $PREFIX: pip install pin==4.1.0" >&2; exit 1; }
EIGEN=""
for d in "$PREFIX/include/eigen3" /usr/include/eigen3; do
  [ -f "$d/Eigen/Core" ] && { EIGEN="$d"; break; }
done
[ -n "$EIGEN" ] || { echo "no Eigen headers: apt-get install libeigen3-dev (or pip install cmeel-eigen)" >&2; exit 1; }

SATSIM_TARGET="$ROOT/target"
if [ "${NATIVE:-0}" = 1 ]; then
  CXXFLAGS="$CXXFLAGS -march=native"
  export RUSTFLAGS="${RUSTFLAGS:-} -C target-cpu=native"
  SATSIM_TARGET="$ROOT/target/native"   # keeps the default build's artefacts apart
fi
echo "== building satsim (cargo build --release -p satsim-cli${RUSTFLAGS:+, RUSTFLAGS='$RUSTFLAGS'})" >&2
(cd "$ROOT" && CARGO_TARGET_DIR="$SATSIM_TARGET" cargo build --release -p satsim-cli --quiet)
SATSIM="$SATSIM_TARGET/release/satsim"

HARNESS="$OUT/harness"
[ "${NATIVE:-0}" = 1 ] && HARNESS="$OUT/harness-native"
FLAGS_FILE="$HARNESS.flags"
BUILD_CMD="$CXX -std=c++17 $CXXFLAGS -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12 -I$PREFIX/include -I$EIGEN $HERE/harness.cpp -o $HARNESS -L$PREFIX/lib -Wl,-rpath,$PREFIX/lib -lboost_serialization"
if [ ! -x "$HARNESS" ] || [ "$HERE/harness.cpp" -nt "$HARNESS" ] || [ "$(cat "$FLAGS_FILE" 2>/dev/null)" != "$BUILD_CMD" ]; then
  echo "== building the Pinocchio harness (about 2 minutes): $BUILD_CMD" >&2
  $BUILD_CMD
  echo "$BUILD_CMD" > "$FLAGS_FILE"
fi

echo "== exporting models and checking satsim dynamics = Pinocchio" >&2
python3 "$HERE/export_models.py" "$OUT" ${ALIGNED:+--aligned} --check "$SATSIM" > /dev/null

RESULTS="$OUT/results.jsonl"
: > "$RESULTS"
for m in $MODELS; do
  # Calls per repetition as `satsim bench` would calibrate them (about 1.5 s per run), from a
  # short probe, without its floor of 100 calls (large models); the same N for both sides.
  probe="$("$SATSIM" bench --model "$OUT/$m.model.toml" --state "$OUT/$m.state.json" --calls 3)"
  calls="$(python3 -c 'import json,sys
t = sum(json.loads(sys.argv[1])["ns_per_call"].values()) * 1e-9 * 8
n = max(1, int(1.5 / t)); p = 1
while p * 10 <= n: p *= 10
print(next(c for c in (5 * p, 2 * p, p, 1) if c <= n))' "$probe")"
  echo "== $m: $ROUNDS rounds of satsim and Pinocchio, $calls calls per repetition" >&2
  # `satsim bench` prints its JSON over several lines: one line per record here.
  for r in $(seq 1 "$ROUNDS"); do
    s() { echo "{\"side\": \"satsim\", \"model\": \"$m\", \"result\": $("$SATSIM" bench --model "$OUT/$m.model.toml" --state "$OUT/$m.state.json" --calls "$calls" | tr -d '\n')}" >> "$RESULTS"; }
    p() { echo "{\"side\": \"pinocchio\", \"model\": \"$m\", \"result\": $("$HARNESS" "$OUT/$m" --calls "$calls")}" >> "$RESULTS"; }
    if [ $((r % 2)) = 1 ]; then s; p; else p; s; fi
  done
done

echo "CPU: $(lscpu | sed -n 's/^Model name: *//p'); satsim: cargo release profile${RUSTFLAGS:+ + RUSTFLAGS='$RUSTFLAGS'}; Pinocchio $(python3 -c 'import pinocchio; print(pinocchio.__version__)'): $CXX $CXXFLAGS, Eigen $EIGEN${ALIGNED:+, aligned revolute joints}"
python3 "$HERE/table.py" "$RESULTS"
