// Reading a view's pixels back (the e2e tests check what was drawn; the canvases need
// preserveDrawingBuffer).

import type * as THREE from "three";

/** RGBA of a region of a renderer's canvas (CSS pixels, rows top first; needs preserveDrawingBuffer). */
export function readPixels(renderer: THREE.WebGLRenderer, x: number, y: number, width: number, height: number): { width: number; height: number; data: Uint8Array } {
  const gl = renderer.getContext();
  const ratio = renderer.getPixelRatio();
  const [px, pw, ph] = [Math.round(x * ratio), Math.max(1, Math.round(width * ratio)), Math.max(1, Math.round(height * ratio))];
  const py = gl.drawingBufferHeight - Math.round(y * ratio) - ph;
  const flipped = new Uint8Array(pw * ph * 4);
  renderer.setRenderTarget(null);
  gl.readPixels(px, py, pw, ph, gl.RGBA, gl.UNSIGNED_BYTE, flipped);
  const data = new Uint8Array(flipped.length);
  for (let row = 0; row < ph; row++) data.set(flipped.subarray((ph - 1 - row) * pw * 4, (ph - row) * pw * 4), row * pw * 4);
  return { width: pw, height: ph, data };
}
