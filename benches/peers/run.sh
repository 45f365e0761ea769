#!/usr/bin/env bash
# One orbit of the peer-comparison spacecraft with satsim, MuJoCo and Basilisk, side by side
# (issue 11). Not run by cargo or CI. Needs Python 3.11+ with `pip install mujoco bsk numpy`
# (PYTHON picks the interpreter; bsk is optional: without it Basilisk is left out).
#
#   bash benches/peers/run.sh                 # 5 alternating rounds
#   ROUNDS=9 PYTHON=/tmp/peers-venv/bin/python bash benches/peers/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release -p satsim-cli
exec "${PYTHON:-python3}" benches/peers/peers.py
