#!/usr/bin/env bash
# The Python package: a fresh venv (target/py-venv), the wheel built from this checkout
# (maturin, release profile, sharing target/ with the Rust build), its abi3/cp39 tag checked,
# then pytest on python/tests. Usage: scripts/test-python.sh [pytest args...]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
venv="$root/target/py-venv"
export PATH="$venv/bin:$PATH"
python="${PYTHON:-python3}"
if [ ! -x "$venv/bin/python" ]; then
  "$python" -m venv "$venv"
fi
"$venv/bin/python" -m pip install -q --upgrade pip
"$venv/bin/python" -m pip install -q "maturin>=1.9,<2" numpy "dask[distributed]" "compas>=2" pytest mypy ruff jsonschema types-jsonschema
# Python code is typed and formatted (python/pyproject.toml: [tool.mypy], [tool.ruff]).
(cd "$root/python" && "$venv/bin/ruff" format --check . && "$venv/bin/ruff" check . && "$venv/bin/mypy")
wheels="$root/target/py-wheels"
rm -rf "$wheels"
# --no-build-isolation: use the venv's maturin (no second download); the wheel is abi3.
"$venv/bin/python" -m pip wheel -q --no-deps --no-build-isolation -w "$wheels" ./python
wheel="$(ls "$wheels"/kappe-*.whl)"
case "$(basename "$wheel")" in
  *-cp39-abi3-*.whl) echo "wheel: $(basename "$wheel") (abi3, CPython >= 3.9)" ;;
  *) echo "error: the wheel $(basename "$wheel") is not tagged cp39-abi3" >&2; exit 1 ;;
esac
"$venv/bin/python" -m pip install -q --force-reinstall --no-deps "$wheel"
# The tests compare with the CLI built from the same sources: build (or refresh) it unless the
# caller names a binary; a stale binary makes the "equals the CLI" tests fail.
if [ -z "${KAPPE_BIN:-}" ]; then
  cargo build --release -q -p kappe-cli
fi
export KAPPE_BIN="${KAPPE_BIN:-$root/target/release/kappe}"
export KAPPE_WHEEL="$wheel"
# From tests/: `python -m` puts the working directory on sys.path, and python/ holds the
# sources without the native module; the installed package must be the one imported.
cd "$root/python/tests"
exec "$venv/bin/python" -m pytest -q . "$@"
