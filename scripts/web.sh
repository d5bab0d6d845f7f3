#!/usr/bin/env bash
# Builds the viewer as a static web page: index.html, the wasm and its JS glue, into DIR
# (default target/web). Serve the folder with any static server, e.g.
#   python3 -m http.server -d target/web 8000   # then open http://127.0.0.1:8000
# Installs what it needs on first use: the wasm32 target (rustup) and wasm-bindgen-cli at
# the version of the wasm-bindgen crate in Cargo.lock (into ~/.cache/myoslice/tools, kept
# across clones: it takes minutes to build).
# MYOSLICE_WASM_OPT=1 also shrinks the wasm with binaryen's wasm-opt (a recent one).
# Usage: scripts/web.sh [DIR]
set -euo pipefail
# DIR is taken from where the script is called.
out=${1:-}
case "$out" in "" | /*) ;; *) out="$PWD/$out" ;; esac
cd "$(dirname "$0")/.."
root=$(pwd)
target=${CARGO_TARGET_DIR:-$root/target}
out=${out:-$target/web}

rustup target list --installed | grep -qx wasm32-unknown-unknown \
  || rustup target add wasm32-unknown-unknown

# The CLI must be the exact version of the crate the wasm was built with.
version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/"/, "", $3); print $3; exit }' Cargo.lock)
[ -n "$version" ] || { echo "no wasm-bindgen in Cargo.lock" >&2; exit 1; }
tools=${XDG_CACHE_HOME:-$HOME/.cache}/myoslice/tools/wasm-bindgen-$version
bindgen="$tools/bin/wasm-bindgen"
if ! "$bindgen" --version 2>/dev/null | grep -q " $version\$"; then
  echo "installing wasm-bindgen-cli $version into $tools"
  # Not --locked: its lock file names a release the registry no longer serves.
  cargo install --quiet wasm-bindgen-cli --version "$version" --root "$tools"
fi

# The viewer's library as a cdylib (natively it stays an rlib); no debug info in the page.
CARGO_PROFILE_RELEASE_DEBUG=false cargo rustc --quiet --release \
  --target wasm32-unknown-unknown -p myoslice-viewer --lib --crate-type cdylib

mkdir -p "$out"
"$bindgen" --target web --no-typescript --out-dir "$out" --out-name myoslice_viewer \
  "$target/wasm32-unknown-unknown/release/myoslice_viewer.wasm"
# Opt-in: binaryen 108 (Debian 12's) rewrites the module's reference-typed table into one
# the browser refuses (the page does not start), so wasm-opt runs only when asked.
if [ "${MYOSLICE_WASM_OPT:-0}" = 1 ]; then
  wasm-opt -O2 --enable-bulk-memory --enable-nontrapping-float-to-int \
    --enable-reference-types --enable-multivalue --enable-sign-ext --enable-mutable-globals \
    "$out/myoslice_viewer_bg.wasm" -o "$out/myoslice_viewer_bg.wasm"
fi
cp viewer/web/index.html "$out/index.html"
raw=$(wc -c < "$out/myoslice_viewer_bg.wasm")
gz=$(gzip -9c "$out/myoslice_viewer_bg.wasm" | wc -c)
echo "web page in $out: wasm $((raw / 1024)) KiB ($((gz / 1024)) KiB gzipped)"
