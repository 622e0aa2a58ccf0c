#!/usr/bin/env bash
# Builds and installs the Python package (pip install ./python, in a virtual
# environment of its own) and runs its pytest suite against the CLI built by
# `cargo test --release` (target/release/mmbm, or MMBM_BIN).
set -euo pipefail
cd "$(dirname "$0")"
VENV=${MMBM_PY_VENV:-.venv}
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
fi
VENV=$(cd "$VENV" && pwd)
"$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip >/dev/null
"$VENV/bin/python" -m pip install -q --disable-pip-version-check numpy pytest webdataset datasets pillow
echo "== building and installing the Python package (pip install ./python)"
"$VENV/bin/python" -m pip install -q --disable-pip-version-check --force-reinstall --no-deps .
echo "== pytest"
cd tests && "$VENV/bin/pytest" -q -p no:cacheprovider .
