// The 2D view draws colours as given (its renderer outputs without colour-space conversion, like
// the Canvas2D drawing it replaced): a hex colour taken as is, not decoded from sRGB.

import * as THREE from "three";

export function rawColour(hex: number): THREE.Color {
  return new THREE.Color().setHex(hex, THREE.LinearSRGBColorSpace);
}
