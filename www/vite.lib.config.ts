import { defineConfig } from "vite";

// The npm package for web CAM portals (src/lib, the worker-based planner API) as an ES library in
// www/dist-lib: slitpath.js (the API, a few kB) and slitpath-worker.js beside it (the worker with
// the wasm core inlined, so it needs no further file). Types in dist-lib/types (tsc, see
// tsconfig.lib.json). Bundlers (Vite, webpack 5, esbuild) resolve `new URL(…, import.meta.url)`.
export default defineConfig({
  base: "./",
  publicDir: false,
  worker: { format: "es", rollupOptions: { output: { entryFileNames: "slitpath-worker.js" } } },
  build: {
    outDir: "dist-lib",
    emptyOutDir: true,
    target: "es2022",
    lib: { entry: "src/lib/index.ts", formats: ["es"], fileName: "slitpath" },
  },
});
