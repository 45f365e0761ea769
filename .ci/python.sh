#!/usr/bin/env bash
# The Python package (issue 14): `pip install ./python` in a fresh virtual environment, then
# its tests with pytest. Needs the `satsim` binary (`cargo build --release`) for the tests
# that compare with the command line. Usage: bash .ci/python.sh
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
venv=$(mktemp -d "${TMPDIR:-/tmp}/satsim-venv.XXXXXX")
trap 'rm -rf "$venv"' EXIT
python3 -m venv "$venv"
export PIP_DISABLE_PIP_VERSION_CHECK=1
"$venv/bin/pip" install --quiet ./python pytest numpy pandas dask distributed matplotlib
export SATSIM_BIN="$root/target/release/satsim"
if [ ! -x "$SATSIM_BIN" ]; then cargo build --release -p satsim-cli; fi
# From the workspace root, so that `import satsim` finds the installed package (python/satsim
# alone has no native module).
"$venv/bin/python" -m pytest python/tests -q
