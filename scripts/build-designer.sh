#!/usr/bin/env bash
# Builds the designer's WebAssembly (issue 25; crates/designer) into crates/designer/pkg/, which
# the CLI embeds at its build (crates/cli/build.rs) for `kappe designer --out DIR`.
#
# Toolchain (pinned; installed here when missing, on Debian 12 with the project's apt sources):
# * Debian's `rustc-web` 1.96 + `cargo-web` + `rust-web-src` (the standard library's source: std is
#   built for wasm32-unknown-unknown with -Zbuild-std, RUSTC_BOOTSTRAP=1), as the machine's rustup
#   toolchain has no wasm32 target and none can be fetched;
# * `lld` (wasm-ld, the linker);
# * wasm-bindgen-cli 0.2.130, the exact version of the `wasm-bindgen` crate (crates/designer/Cargo.toml
#   pins it with `=`), by `cargo install` into target/designer-tools.
# Outputs: crates/designer/pkg/kappe_designer.js (glue, --target no-modules) and
# kappe_designer_bg.wasm(.gz). Build dir: $KAPPE_WASM_TARGET_DIR (default target/wasm).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
WASM_BINDGEN_VERSION=0.2.130
TARGET_DIR=${KAPPE_WASM_TARGET_DIR:-$ROOT/target/wasm}
TOOLS=${KAPPE_WASM_TOOLS:-$ROOT/target/designer-tools}

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO=sudo; fi
if [ ! -x /usr/bin/rustc ] || ! /usr/bin/rustc --version | grep -q '^rustc 1\.96' \
   || [ ! -d /usr/lib/rustlib/src/rust/library ] || ! command -v wasm-ld >/dev/null 2>&1; then
  echo "installing rustc-web, cargo-web, rust-web-src, lld (apt-get)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    rustc-web cargo-web rust-web-src lld >/dev/null
fi
/usr/bin/rustc --version

if ! "$TOOLS/bin/wasm-bindgen" --version 2>/dev/null | grep -q " $WASM_BINDGEN_VERSION\$"; then
  echo "installing wasm-bindgen-cli $WASM_BINDGEN_VERSION (cargo install)"
  # Not --locked: the crates.io mirror here lacks webpki-roots 1.0.11 of its lock file (the
  # download client's TLS roots, unused by wasm-bindgen itself); the version is pinned exactly.
  CARGO_TARGET_DIR="$TOOLS/build" cargo install wasm-bindgen-cli --version "$WASM_BINDGEN_VERSION" \
    --root "$TOOLS" --quiet
fi

# Debian's compiler and cargo for the wasm build only (the rest of the workspace: rustup stable).
# simd128: faer's kernels (pulp, gemm) take their 128-bit WebAssembly SIMD paths instead of the
# scalar fallback in the buckling workers; Chromium ≥ 91, Firefox ≥ 89 and Safari ≥ 16.4 run it.
# std is rebuilt with the same flag (-Zbuild-std).
env PATH="/usr/bin:$PATH" RUSTC=/usr/bin/rustc RUSTDOC=/usr/bin/rustdoc RUSTC_BOOTSTRAP=1 \
  RUSTFLAGS="-C target-feature=+simd128" \
  CARGO_TARGET_DIR="$TARGET_DIR" CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER=wasm-ld \
  /usr/bin/cargo build --release -p kappe-designer --target wasm32-unknown-unknown \
  -Zbuild-std=std,panic_abort

PKG=crates/designer/pkg
mkdir -p "$PKG"
"$TOOLS/bin/wasm-bindgen" --target no-modules --no-typescript --out-dir "$PKG" \
  "$TARGET_DIR/wasm32-unknown-unknown/release/kappe_designer.wasm"
# The page inlines the wasm gzip-compressed (base64), unpacked by the browser's
# DecompressionStream: 4.9 MB of wasm would not fit the 5 MB page otherwise.
gzip -9 -n -c "$PKG/kappe_designer_bg.wasm" > "$PKG/kappe_designer_bg.wasm.gz"
ls -l "$PKG"
