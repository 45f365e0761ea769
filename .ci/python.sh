#!/usr/bin/env bash
# The Python package (issue 14): `pip install ./python` in a fresh virtual environment, then
# its tests with pytest. Needs the `satsim` binary for the tests that compare with the command
# line. Usage: bash .ci/python.sh
#
# The wheel and the binary are built in the release profile, or in $SATSIM_PYTHON_PROFILE:
# `.ci/run` passes `dev`, the profile `cargo test --workspace` has just compiled, and then
# fails if the wheel compiled any crate of the workspace but this package's own (the features
# python/Cargo.toml lines up): compiling the kernel's lanes again costs CI many minutes.
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
profile=${SATSIM_PYTHON_PROFILE:-release}
case "$profile" in dev) dir=debug ;; *) dir=$profile ;; esac
export MATURIN_PEP517_ARGS="--profile $profile"
log="$venv/pip.log"
if ! "$venv/bin/pip" install -v "./python[examples,test,gym,ray]" pin==4.1.0 > "$log" 2>&1; then
  tail -n 60 "$log"; exit 1
fi
grep -E '^ *(Compiling|Finished) ' "$log" || true
if [ "$profile" = dev ] && grep -E '^ *Compiling satsim-(tree|environment|integrate|satellite|spacecraft|tools) ' "$log"; then
  echo "error: the wheel compiled the crates above again: their dependencies' features differ from those of \`cargo test --workspace\` (see the note in python/Cargo.toml)" >&2
  exit 1
fi
"$venv/bin/python" -c "import pinocchio; print('pinocchio', pinocchio.__version__)"
export SATSIM_BIN="${CARGO_TARGET_DIR:-$root/target}/$dir/satsim"
if [ ! -x "$SATSIM_BIN" ]; then cargo build --profile "$profile" -p satsim-cli; fi
# The live Pinocchio tests fail rather than skip when Pinocchio is missing.
export SATSIM_REQUIRE_PINOCCHIO=1
# The same for satsim.gym's tests and Gymnasium (the `gym` extra).
export SATSIM_REQUIRE_GYM=1
# And for the Ray executor's test (the `ray` extra).
export SATSIM_REQUIRE_RAY=1
# From the workspace root, so that `import satsim` finds the installed package (python/satsim
# alone has no native module).
"$venv/bin/python" -m pytest python/tests -q -rs
