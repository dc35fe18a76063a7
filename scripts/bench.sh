#!/usr/bin/env bash
# Benchmarks, native and wasm (headless Chromium), on the same cases (src/bench.rs): the mesh stage
# on a 1-million-triangle STL and the conformal core (flatten + slit map) on the analytic parts
# (natively also on ../shared/meshes when present), the path length at equal finish on generated
# parts, the flank strategy on a blade, STEP import of a 20-face file and
# the Coons band spiral; then the page itself on generated parts of 10k, 40k
# and 300k faces (scripts/bench-page.sh). Prints figures; asserts nothing about time.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$HOME/.cargo/bin:$PATH"
echo "=== native ==="
cargo bench --bench mesh --bench conformal --bench origin --bench verify --bench plan --bench length --bench flank --bench fuzz --bench sweep --bench step 2>&1 | grep -v -E '^\s*(Compiling|Finished|Running)'
echo "=== wasm (headless Chromium) ==="
# The cases run synchronously in the page for tens of seconds; the runner's default 20 s budget
# (also its per-request timeout while polling the page) is too short for them.
export WASM_BINDGEN_TEST_TIMEOUT=900
wasm-pack test --headless --chrome --release -- --test wasm_bench -- --nocapture 2>&1 |
  grep -v -E '^\s*(Compiling|Finished|Running|Blocking)|^\[INFO\]'
echo "=== the page (headless Chromium) ==="
bash scripts/bench-page.sh
