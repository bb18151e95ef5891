#!/usr/bin/env bash
# End-to-end test and speed table of the designer page (issue 25), called by .ci/run after
# scripts/build-designer.sh: writes the page with `kappe designer`, opens it from file:// in
# headless Debian `chromium` driven by playwright-core (installed as for web/e2e/run.sh) and checks
# it against `kappe design` (designer.test.mjs); then prints the speed table (bench.mjs).
set -euo pipefail
cd "$(dirname "$0")/../.."

if ! command -v chromium >/dev/null 2>&1; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO=sudo; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    chromium fonts-dejavu-core >/dev/null
fi
[ -d web/node_modules/playwright-core ] || (cd web && npm ci --no-audit --no-fund --loglevel=error)

test -f crates/designer/pkg/kappe_designer_bg.wasm.gz || {
  echo "run scripts/build-designer.sh first" >&2
  exit 2
}
cargo build --release --quiet -p kappe-cli
BIN=$(cargo metadata --format-version 1 --no-deps | node -e 'let s="";process.stdin.on("data",d=>s+=d).on("end",()=>console.log(JSON.parse(s).target_directory))')/release/kappe
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
"$BIN" designer --out "$OUT/designer"
SIZE=$(stat -c %s "$OUT/designer/designer.html")
echo "designer.html: $SIZE bytes"
if [ "$SIZE" -gt 5000000 ]; then
  echo "designer.html is larger than 5 MB" >&2
  exit 1
fi
KAPPE_DESIGNER="$OUT/designer/designer.html" KAPPE_BIN="$BIN" node --test web/designer/designer.test.mjs
KAPPE_BENCH_MOVES=${KAPPE_BENCH_MOVES:-3} node web/designer/bench.mjs "$OUT/designer/designer.html"
