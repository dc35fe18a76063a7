import { defineConfig } from "vite";

// The page lives in www/; the wasm package is built into www/pkg by wasm-pack (--target web) and
// imported by src/core.ts only. The planner runs in a module Web Worker.
export default defineConfig({
  base: "./",
  worker: { format: "es" },
  // three.js alone is ~500 kB minified: one chunk is fine for a page loaded once (and cached).
  build: { outDir: "dist", emptyOutDir: true, target: "es2022", chunkSizeWarningLimit: 1200 },
  server: { host: "127.0.0.1", port: 5173, strictPort: true },
  preview: { host: "127.0.0.1", port: 4173, strictPort: true },
});
