#!/usr/bin/env bash
# End-to-end test of the HTML report (issues 8, 14), called by .ci/run:
# writes the demo report, opens it from file:// in headless Debian `chromium` driven by
# playwright-core (never `playwright`, never a browser download) and checks it (report.test.mjs).
# Installs what a fresh machine lacks: chromium via apt-get, playwright-core via `npm ci`.
set -euo pipefail
cd "$(dirname "$0")/../.."

if ! command -v chromium >/dev/null 2>&1; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO=sudo; fi
  echo "installing chromium (apt-get)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    chromium fonts-dejavu-core >/dev/null
fi
chromium --version 2>/dev/null | head -1 || true

# The committed three.js bundle is the one web/build.sh recorded.
(cd crates/report/assets && sha256sum -c --quiet three-vendor.min.js.sha256)

(cd web && npm ci --no-audit --no-fund --loglevel=error)

OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
cargo run --release --quiet -p kappe-report --example demo -- "$OUT/report.html"
KAPPE_REPORT="$OUT/report.html" node --test web/e2e/

# The same checks on a report written by `kappe design` itself: a short cap with the analysis
# and the robot plan, so every panel of the page holds real data. Release builds throughout:
# scripts/test.sh has built them already, so CI compiles the workspace once, not twice.
printf '[cap]\nlength = 0.15\n' > "$OUT/short.toml"
cargo run --release --quiet -p kappe-cli -- design "$OUT/short.toml" --out "$OUT/design" --quiet --states every:4
KAPPE_REPORT="$OUT/design/report.html" node --test web/e2e/

# A base that moves while printing (issue 27): the arm rides on the base trajectory, so the drawn
# nozzle stays on the layer being printed (the test's nozzle check fails if the viewer left the
# base at its start).
printf '[cap]\nlength = 0.15\n[robot.beams]\noverrun = 0.05\n[robot.base]\nmode = "moving"\n[robot.tolerance]\nverdict = false\n' > "$OUT/moving.toml"
cargo run --release --quiet -p kappe-cli -- design "$OUT/moving.toml" --out "$OUT/moving" --quiet --states every:4
KAPPE_REPORT="$OUT/moving/report.html" node --test web/e2e/

# A failing design (a flat, wide cap: sigma_min fails): the page must work just as well, with
# the failing rows and their places.
printf '[cap]\nspan = 1.4\nrise = 0.12\nlength = 0.15\n' > "$OUT/fail.toml"
cargo run --release --quiet -p kappe-cli -- design "$OUT/fail.toml" --out "$OUT/fail" --quiet --states every:4 --allow-fail
KAPPE_REPORT="$OUT/fail/report.html" node --test web/e2e/
