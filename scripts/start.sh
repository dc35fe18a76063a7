#!/usr/bin/env bash
# Sets everything up, builds the wasm package (release), writes the bundled sample part, and
# serves the page with Vite on http://127.0.0.1:5173/ (PORT=… to change). Ctrl-C stops it.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PWD/node_modules/.bin:$PATH"
PORT=${PORT:-5173}
URL="http://127.0.0.1:$PORT/"

say() { printf '\n\033[1m[start]\033[0m %s\n' "$*"; }

bash scripts/setup.sh

say "building the wasm package (release) into www/pkg"
wasm-pack build --target web --out-dir www/pkg --release

say "writing the sample parts www/public/samples/freeform_4_holes.stl, blade.stl (flank) and blade_band.step (Coons)"
mkdir -p www/public/samples
cargo run --release --quiet --bin slitpath -- fixture freeform_4_holes -o www/public/samples/freeform_4_holes.stl
cargo run --release --quiet --bin slitpath -- fixture blade -o www/public/samples/blade.stl
cargo run --release --quiet --bin slitpath -- fixture step:blade_band -o www/public/samples/blade_band.step

say "serving the page with Vite on $URL"
vite www --host 127.0.0.1 --port "$PORT" --strictPort --clearScreen false &
server=$!
trap 'kill "$server" 2>/dev/null || true' EXIT INT TERM

# Wait until the server answers, then print the address where nobody can miss it.
for _ in $(seq 1 150); do
  if (exec 3<>"/dev/tcp/127.0.0.1/$PORT") 2>/dev/null; then
    printf '\n\033[1;32m  slitpath is running: open %s\033[0m  (Ctrl-C to stop)\n\n' "$URL"
    break
  fi
  kill -0 "$server" 2>/dev/null || { echo "[start] the server stopped (is port $PORT already in use? PORT=… picks another)" >&2; exit 1; }
  sleep 0.2
done
wait "$server"
