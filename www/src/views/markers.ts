// The 2D view's markers, in screen pixels: the pole (a star), the pole picked by hand (a ring) and
// the cursor (a white dot with a dark rim).

import * as THREE from "three";
import { rawColour } from "./raw-colour";

const flat = (geometry: THREE.BufferGeometry, hex: number, z: number): THREE.Mesh => {
  const mesh = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ color: rawColour(hex), depthTest: false, depthWrite: false }));
  mesh.position.z = z;
  mesh.renderOrder = 10 + z;
  return mesh;
};

function starGeometry(outer: number, inner: number): THREE.ShapeGeometry {
  const shape = new THREE.Shape();
  for (let k = 0; k < 10; k++) {
    const r = k % 2 === 0 ? outer : inner;
    const a = Math.PI / 2 + (k * Math.PI) / 5; // y up: the first tip points up
    if (k === 0) shape.moveTo(r * Math.cos(a), r * Math.sin(a));
    else shape.lineTo(r * Math.cos(a), r * Math.sin(a));
  }
  return new THREE.ShapeGeometry(shape);
}

export function star(hex: number): THREE.Object3D {
  return flat(starGeometry(8, 3.5), hex, 0);
}

export function ring(hex: number): THREE.Object3D {
  return flat(new THREE.RingGeometry(5.75, 8.25, 32), hex, 1);
}

export function dot(hex: number): THREE.Object3D {
  const group = new THREE.Group();
  group.add(flat(new THREE.CircleGeometry(6.25, 32), hex, 2), flat(new THREE.CircleGeometry(3.75, 32), 0xffffff, 3));
  return group;
}
