#!/usr/bin/env bash
# Idempotent set-up for a Debian/Ubuntu machine that reaches only the package registries
# (crates.io, npm, Debian). Installs, only when missing or at the wrong version:
#   - the Rust target wasm32-unknown-unknown (rustup)
#   - wasm-pack and wasm-bindgen-cli, pinned (cargo install; the CLI must equal the
#     `wasm-bindgen` crate pinned in Cargo.toml)
#   - Debian's chromium + chromium-driver (headless browser tests) and linuxcnc-uspace (`rs274`,
#     LinuxCNC's standalone G-code interpreter) with apt-get, --no-install-recommends
#   - the npm packages of the page (npm ci, top-level package-lock.json)
# Nothing here downloads a browser or a prebuilt binary. Safe to run again and again: a second
# run only checks versions (about a second).
set -euo pipefail
cd "$(dirname "$0")/.."

WASM_PACK_VERSION=0.15.1
# Must equal the `wasm-bindgen` version pinned in Cargo.toml / Cargo.lock.
WASM_BINDGEN_VERSION=$(sed -n 's/^wasm-bindgen = { version = "=\([0-9.]*\)".*/\1/p' Cargo.toml)
[ -n "$WASM_BINDGEN_VERSION" ] || { echo "setup: cannot read the wasm-bindgen pin from Cargo.toml" >&2; exit 1; }
NODE_MIN=20.19 # Vite 7 needs Node ^20.19 or >= 22.12

say() { printf '\033[1m[setup]\033[0m %s\n' "$*"; }
die() { printf '\033[1;31m[setup]\033[0m %s\n' "$*" >&2; exit 1; }

export PATH="$HOME/.cargo/bin:$PATH"

command -v cargo >/dev/null && command -v rustup >/dev/null ||
  die "Rust is missing: install it with rustup (https://rustup.rs), then run this again"
command -v node >/dev/null && command -v npm >/dev/null || die "Node.js $NODE_MIN+ and npm are missing"
node -e "const [a,b]=process.versions.node.split('.').map(Number);const [x,y]='$NODE_MIN'.split('.').map(Number);process.exit(a>x||(a===x&&b>=y)?0:1)" ||
  die "Node.js $(node --version) is too old: $NODE_MIN or newer is needed"

if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
  say "adding rust target wasm32-unknown-unknown"
  rustup target add wasm32-unknown-unknown
fi

# cargo install, pinned; --locked first (the crate's own lock file), and when a locked
# dependency is not (or no longer) in the registry, the newest compatible versions.
cargo_install() {
  local crate=$1 version=$2
  say "installing $crate $version (cargo install, a few minutes)"
  cargo install --locked --force "$crate" --version "$version" ||
    { say "$crate: the locked dependencies do not resolve here; installing with fresh ones"
      cargo install --force "$crate" --version "$version"; }
}

if [ "$(wasm-pack --version 2>/dev/null)" != "wasm-pack $WASM_PACK_VERSION" ]; then
  cargo_install wasm-pack "$WASM_PACK_VERSION"
fi

if [ "$(wasm-bindgen --version 2>/dev/null)" != "wasm-bindgen $WASM_BINDGEN_VERSION" ] ||
  [ "$(wasm-bindgen-test-runner --version 2>/dev/null)" != "wasm-bindgen-test-runner $WASM_BINDGEN_VERSION" ]; then
  cargo_install wasm-bindgen-cli "$WASM_BINDGEN_VERSION"
fi

apt_missing=()
command -v chromium >/dev/null || apt_missing+=(chromium)
command -v chromedriver >/dev/null || apt_missing+=(chromium-driver)
command -v rs274 >/dev/null || apt_missing+=(linuxcnc-uspace)
if [ ${#apt_missing[@]} -gt 0 ]; then
  say "apt-get install ${apt_missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${apt_missing[@]}"
fi

# npm packages (Vite, TypeScript): reinstall only when package-lock.json changed.
if [ ! -f node_modules/.package-lock.json ] || [ package-lock.json -nt node_modules/.package-lock.json ]; then
  say "npm ci"
  npm ci --no-audit --no-fund
fi

say "ready: $(rustc --version | cut -d' ' -f1-2), $(wasm-pack --version), $(wasm-bindgen --version)," \
  "$(chromium --version 2>/dev/null | head -1), node $(node --version), rs274 at $(command -v rs274)"
