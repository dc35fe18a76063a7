#!/usr/bin/env bash
# Runs every test of slitpath, each step under a clear header, and ends with a summary table and
# the line "N passed, N failed" (steps). Exits non-zero when any step failed.
# Every step runs even when an earlier one failed, so one run shows everything that is wrong.
set -uo pipefail # no -e: a failing step is recorded, not fatal
cd "$(dirname "$0")/.."
ROOT=$PWD
export PATH="$HOME/.cargo/bin:$ROOT/node_modules/.bin:$PATH"

bold=$'\033[1m' green=$'\033[32m' red=$'\033[31m' reset=$'\033[0m'
if [ ! -t 1 ]; then bold="" green="" red="" reset=""; fi

names=() results=() seconds=()

# The bundled sample parts, written by the CLI into www/public (copied into the page build): the
# spiral's freeform part, the flank strategy's blade and the STEP blade band (Coons band strategy).
sample_part() {
  mkdir -p www/public/samples
  cargo run --release --quiet --bin slitpath -- fixture freeform_4_holes -o www/public/samples/freeform_4_holes.stl
  cargo run --release --quiet --bin slitpath -- fixture blade -o www/public/samples/blade.stl
  cargo run --release --quiet --bin slitpath -- fixture step:blade_band -o www/public/samples/blade_band.step
}

# step NAME COMMAND...: runs the command in a subshell with `set -e` (so a multi-command
# function stops at its first failure) and records the outcome. Never call it as the condition
# of `if`, `&&` or `||`: bash ignores `set -e` inside such a call; test $? afterwards instead.
step() {
  local name=$1
  shift
  printf '\n%s━━━ [%d] %s ━━━%s\n%s$ %s%s\n' "$bold" $((${#names[@]} + 1)) "$name" "$reset" "$bold" "$*" "$reset"
  local start=$SECONDS rc
  (
    set -e
    "$@"
  )
  rc=$?
  names+=("$name")
  seconds+=($((SECONDS - start)))
  if [ "$rc" -eq 0 ]; then
    results+=(PASS)
    printf '%s✔ %s passed (%ds)%s\n' "$green" "$name" $((SECONDS - start)) "$reset"
  else
    results+=(FAIL)
    printf '%s✘ %s FAILED (exit %d, %ds)%s\n' "$red" "$name" "$rc" $((SECONDS - start)) "$reset"
  fi
  return "$rc"
}

# A step that cannot run because one it needs failed.
skip() {
  names+=("$1")
  seconds+=(0)
  results+=(FAIL)
  printf '\n%s━━━ [%d] %s ━━━%s\n%s✘ not run: %s%s\n' "$bold" ${#names[@]} "$1" "$reset" "$red" "$2" "$reset"
}

summary() {
  local passed=0 failed=0 i
  printf '\n%s━━━ summary ━━━%s\n' "$bold" "$reset"
  printf '%-4s  %-52s  %6s\n' "" "step" "time"
  for i in "${!names[@]}"; do
    local colour=$green
    [ "${results[$i]}" = PASS ] || colour=$red
    printf '%s%-4s%s  %-52s  %5ss\n' "$colour" "${results[$i]}" "$reset" "${names[$i]}" "${seconds[$i]}"
    if [ "${results[$i]}" = PASS ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
  done
  printf 'total time %ds\n' "$SECONDS"
  printf '%d passed, %d failed\n' "$passed" "$failed"
  [ "$failed" -eq 0 ]
}

step "set-up (scripts/setup.sh)" bash scripts/setup.sh
if [ $? -ne 0 ]; then
  for s in "rustfmt" "clippy (native, all targets)" "clippy (wasm32 library)" "cargo test (native, release)" \
    "wasm facade in headless Chromium" "wasm package for the page" "sample part (CLI: slitpath fixture)" \
    "page type check (tsc)" "page build (vite)" "npm package for portals (vite library + types)" \
    "page and package in headless Chromium (Playwright)"; do
    skip "$s" "the set-up failed"
  done
  summary
  exit 1
fi

step "rustfmt" cargo fmt --check
step "clippy (native, all targets)" cargo clippy --all-targets -- -D warnings
step "clippy (wasm32 library)" cargo clippy --lib --target wasm32-unknown-unknown -- -D warnings
step "cargo test (native, release)" cargo test --release
# Only the browser tests (tests/wasm.rs): the native test files are not meant for wasm32.
# The browser's capabilities (headless, no sandbox as root, Debian's binary) are in webdriver.json.
# The runner's default 20 s budget is also its per-request timeout while the page computes.
export WASM_BINDGEN_TEST_TIMEOUT=300
step "wasm facade in headless Chromium" wasm-pack test --headless --chrome --release -- --test wasm

step "wasm package for the page" wasm-pack build --target web --out-dir www/pkg --release
wasm_ok=$?
step "sample part (CLI: slitpath fixture)" sample_part
sample_ok=$?
if [ $wasm_ok -eq 0 ]; then
  step "page type check (tsc)" tsc --noEmit -p www
  step "page build (vite)" vite build www --logLevel warn
  build_ok=$?
  step "npm package for portals (vite library + types)" npm run --silent build:lib
  lib_ok=$?
else
  for s in "page type check (tsc)" "page build (vite)" "npm package for portals (vite library + types)"; do
    skip "$s" "the wasm package did not build"
  done
  build_ok=1 lib_ok=1
fi
# Playwright (playwright-core) drives Debian's /usr/bin/chromium; screenshots go to test-output/.
if [ $build_ok -eq 0 ] && [ $lib_ok -eq 0 ] && [ $sample_ok -eq 0 ]; then
  step "page and package in headless Chromium (Playwright)" node --test --test-concurrency=1 --test-reporter=spec tests/e2e/page.test.mjs tests/e2e/flank-page.test.mjs tests/e2e/large-part.test.mjs tests/e2e/library.test.mjs tests/e2e/step-page.test.mjs
else
  skip "page and package in headless Chromium (Playwright)" "the page, the package or the sample part did not build"
fi

summary
