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
# The package with its `examples` extra (matplotlib, pandas, Dask: what examples/python/*.py
# import, tested in python/tests), `test` extra and `gym` extra (Gymnasium, for satsim.gym), and Pinocchio (PyPI `pin`, the version
# tests/fixtures/pinocchio/ was made with) for the live check on random trees.
"$venv/bin/pip" install --quiet "./python[examples,test,gym]" pin==4.1.0
"$venv/bin/python" -c "import pinocchio; print('pinocchio', pinocchio.__version__)"
export SATSIM_BIN="$root/target/release/satsim"
if [ ! -x "$SATSIM_BIN" ]; then cargo build --release -p satsim-cli; fi
# The live Pinocchio tests fail rather than skip when Pinocchio is missing.
export SATSIM_REQUIRE_PINOCCHIO=1
# The same for satsim.gym's tests and Gymnasium (the `gym` extra).
export SATSIM_REQUIRE_GYM=1
# From the workspace root, so that `import satsim` finds the installed package (python/satsim
# alone has no native module).
"$venv/bin/python" -m pytest python/tests -q -rs
