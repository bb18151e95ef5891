#!/usr/bin/env bash
# The project's test command (README): unit, integration and doc tests of the whole workspace,
# then the Python package's tests (fresh venv in target/py-venv, wheel built from this checkout).
# Built in the release profile, so the README's main job (`cargo run --release -p kappe-cli`)
# and the tests share one build of every dependency (issue 16: set-up time on a fresh machine).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release --workspace --all-targets
cargo test --release --workspace --doc
bash scripts/test-python.sh
