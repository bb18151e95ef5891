#!/usr/bin/env bash
# Regenerates the vendored three.js bundle that crates/report inlines into report.html.
# `cargo build` never runs this: the bundle is committed. Run it only to upgrade three:
#   bash web/build.sh
# It installs the exact versions of package-lock.json, bundles three + OrbitControls into one
# minified IIFE (ES modules cannot import sibling files from file://, and the report must open
# offline), keeps three's licence comment (at the end of the file), copies three's LICENSE and records the sha256.
set -euo pipefail
cd "$(dirname "$0")"
THREE_VERSION=$(node -p "require('./package.json').devDependencies.three")
ASSETS=../crates/report/assets
OUT="$ASSETS/three-vendor.min.js"
npm ci --no-audit --no-fund
npx esbuild vendor-entry.js --bundle --minify --format=iife --target=es2020 \
  --legal-comments=eof --outfile="$OUT"
cp node_modules/three/LICENSE "$ASSETS/three-LICENSE.txt"
# The report escapes `</script` itself; make sure the bundle holds no HTML comment opener either,
# which would change how the HTML parser ends the inline <script>.
if grep -q '<!--' "$OUT"; then echo "bundle contains '<!--'" >&2; exit 1; fi
( cd "$ASSETS" && sha256sum three-vendor.min.js > three-vendor.min.js.sha256 )
echo "three $THREE_VERSION" > "$ASSETS/three-vendor.version"
ls -l "$OUT"; cat "$ASSETS/three-vendor.min.js.sha256"
