#!/usr/bin/env bash
# The page benchmark (npm run bench:page): builds the wasm package and the page as `npm test`
# does, then times the page in headless Chromium on generated parts (tests/e2e/bench-page.mjs).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PWD/node_modules/.bin:$PATH"
wasm-pack build --target web --out-dir www/pkg --release
mkdir -p www/public/samples
cargo build --release --quiet --bin slitpath
cargo run --release --quiet --bin slitpath -- fixture freeform_4_holes -o www/public/samples/freeform_4_holes.stl
vite build www --logLevel warn
node tests/e2e/bench-page.mjs
