// The faces of a STEP file in the 3D view (render worker): every face in a colour of its own,
// the selected ones bright and the others pale grey-tinted; faces the part's own surface covers
// (the planned selection, drawn with its heat map) are left out so nothing is drawn twice.
// A click picks the face under the pointer (a ray against all faces, covered or not).

import * as THREE from "three";
import type { StepDrawing } from "../lib/index";

/** A hue per face (golden-angle steps: neighbours differ), saturated when selected. */
function faceColour(face: number, selected: boolean): [number, number, number] {
  const c = new THREE.Color().setHSL(((face * 0.381966) % 1 + 1) % 1, selected ? 0.65 : 0.12, selected ? 0.55 : 0.8);
  return [c.r, c.g, c.b];
}

export class FacesLayer {
  readonly mesh: THREE.Mesh<THREE.BufferGeometry, THREE.MeshStandardMaterial>;
  /** All triangles, for picking (the drawn index leaves covered faces out). */
  private readonly pickMesh: THREE.Mesh;
  private readonly raycaster = new THREE.Raycaster();

  constructor(private readonly drawing: StepDrawing) {
    const geometry = new THREE.BufferGeometry();
    const position = new THREE.BufferAttribute(drawing.positions, 3);
    geometry.setAttribute("position", position);
    geometry.setAttribute("normal", new THREE.BufferAttribute(drawing.normals, 3));
    geometry.setAttribute("color", new THREE.BufferAttribute(new Float32Array(drawing.positions.length), 3));
    geometry.setIndex(new THREE.BufferAttribute(drawing.triangles.slice(), 1));
    geometry.computeBoundingBox();
    const material = new THREE.MeshStandardMaterial({ vertexColors: true, side: THREE.DoubleSide, roughness: 0.6, metalness: 0.05, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
    this.mesh = new THREE.Mesh(geometry, material);
    const pick = new THREE.BufferGeometry();
    pick.setAttribute("position", position);
    pick.setIndex(new THREE.BufferAttribute(drawing.triangles, 1));
    pick.computeBoundingSphere();
    this.pickMesh = new THREE.Mesh(pick, new THREE.MeshBasicMaterial({ side: THREE.DoubleSide }));
    const faces = this.faceCount();
    this.setState(new Uint8Array(faces), new Uint8Array(faces));
  }

  faceCount(): number {
    let n = 0;
    for (const f of this.drawing.faceOfTriangle) n = Math.max(n, f + 1);
    return n;
  }

  /** `selected[f]`, `covered[f]`: 1 or 0 per face (list order). */
  setState(selected: Uint8Array, covered: Uint8Array): void {
    const colours = this.mesh.geometry.getAttribute("color") as THREE.BufferAttribute;
    const array = colours.array as Float32Array;
    const palette = new Map<number, [number, number, number]>();
    const { faceOfVertex, faceOfTriangle, triangles } = this.drawing;
    for (let v = 0; v < faceOfVertex.length; v++) {
      const f = faceOfVertex[v]!;
      const key = 2 * f + (selected[f] ? 1 : 0);
      let c = palette.get(key);
      if (c === undefined) palette.set(key, (c = faceColour(f, selected[f] === 1)));
      array.set(c, 3 * v);
    }
    colours.needsUpdate = true;
    const kept: number[] = [];
    for (let t = 0; t < faceOfTriangle.length; t++) {
      if (covered[faceOfTriangle[t]!]) continue;
      kept.push(triangles[3 * t]!, triangles[3 * t + 1]!, triangles[3 * t + 2]!);
    }
    this.mesh.geometry.setIndex(new THREE.BufferAttribute(Uint32Array.from(kept), 1));
  }

  /** The face (list index) under the screen point `ndc` (−1..1), or null. */
  faceAt(ndc: THREE.Vector2, camera: THREE.Camera): number | null {
    this.raycaster.setFromCamera(ndc, camera);
    const hit = this.raycaster.intersectObject(this.pickMesh)[0];
    return hit?.faceIndex != null ? this.drawing.faceOfTriangle[hit.faceIndex]! : null;
  }

  /**
   * A screen point (ndc) where face `face` is the first thing under the pointer, or null when it
   * is hidden from this view (the tests click there).
   */
  visiblePoint(face: number, camera: THREE.Camera): THREE.Vector2 | null {
    const { faceOfTriangle, triangles, positions } = this.drawing;
    const p = new THREE.Vector3();
    let tries = 0;
    for (let t = 0; t < faceOfTriangle.length && tries < 300; t++) {
      if (faceOfTriangle[t] !== face || t % 5 !== 0) continue;
      p.set(0, 0, 0);
      for (let k = 0; k < 3; k++) {
        const v = triangles[3 * t + k]!;
        p.x += positions[3 * v]! / 3;
        p.y += positions[3 * v + 1]! / 3;
        p.z += positions[3 * v + 2]! / 3;
      }
      const ndc = p.clone().project(camera);
      if (Math.abs(ndc.x) > 0.9 || Math.abs(ndc.y) > 0.9) continue;
      tries++;
      const at = new THREE.Vector2(ndc.x, ndc.y);
      if (this.faceAt(at, camera) === face) return at;
    }
    return null;
  }

  box(): THREE.Box3 {
    return this.mesh.geometry.boundingBox!;
  }

  dispose(): void {
    this.mesh.removeFromParent();
    this.mesh.geometry.dispose();
    this.mesh.material.dispose();
    this.pickMesh.geometry.dispose();
  }
}
