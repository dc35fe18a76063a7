// three.js objects the views share: line segments from a polyline, indexed geometry, disposal.

import * as THREE from "three";
import type { Polyline } from "../lib/index";

/** A polyline (see lib/drawing) as line segments with a colour per vertex. */
export function polylineObject(p: Polyline): THREE.LineSegments {
  const g = geometry(new THREE.BufferAttribute(p.positions, 3), p.segments);
  g.setAttribute("color", new THREE.BufferAttribute(p.colours, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ vertexColors: true }));
}

/** A geometry of `position` with the index `index` (triangles or segment pairs). */
export function geometry(position: THREE.BufferAttribute, index: Uint32Array): THREE.BufferGeometry {
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", position);
  g.setIndex(new THREE.BufferAttribute(index, 1));
  return g;
}

/** Removes an object from its parent and frees its geometries and materials. */
export function dispose(object: THREE.Object3D | null): void {
  if (object === null) return;
  object.removeFromParent();
  object.traverse((node) => {
    const mesh = node as Partial<THREE.Mesh>;
    mesh.geometry?.dispose();
    const material = mesh.material;
    if (Array.isArray(material)) material.forEach((m) => m.dispose());
    else material?.dispose();
  });
}
