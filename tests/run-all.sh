#!/usr/bin/env bash
# Every test: cargo's (the workspace, release profile), then the Python
# module's pytest suite in a virtual environment (target/pyenv) into which
# the module is built and installed from this checkout. Arguments go to
# cargo test (e.g. `-- --ignored`).
set -euo pipefail
cd "$(dirname "$0")/.."

cargo test --workspace --release "$@"

venv=target/pyenv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/pip" install -q --disable-pip-version-check numpy pytest tqdm
# The wheel as a user installs it (plugins bundled); reinstalled every run
# so the tests see this checkout's code.
"$venv/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps ./host/python
"$venv/bin/python" -m pytest host/python/tests -q
