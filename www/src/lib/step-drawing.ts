// What the 3D view draws of a STEP file's faces (built in the planner worker): the tessellation
// with every face's vertices of its own (so each face takes one colour and the edges between
// faces stay sharp), their normals, and the face (index into the face list) of every vertex and
// triangle, for colouring by selection and for picking.

import type { StepFacesOutput } from "../core";
import { vertexNormals } from "./flank-drawing";

export interface StepDrawing {
  positions: Float32Array;
  normals: Float32Array;
  triangles: Uint32Array;
  /** Index into the face list of every vertex and every triangle. */
  faceOfVertex: Uint32Array;
  faceOfTriangle: Uint32Array;
}

export function stepDrawing(faces: StepFacesOutput): StepDrawing {
  const index = new Map(faces.faces.map((f, i) => [f.id, i]));
  const triangleCount = faces.triangles.length / 3;
  const faceOfTriangle = new Uint32Array(triangleCount);
  // A vertex shared by k faces becomes k vertices: key = vertex · faces + face.
  const n = faces.faces.length;
  const remap = new Map<number, number>();
  const triangles = new Uint32Array(faces.triangles.length);
  const source: number[] = [];
  const faceOfVertex: number[] = [];
  for (let t = 0; t < triangleCount; t++) {
    const f = index.get(faces.faceOfTriangle[t]!) ?? 0;
    faceOfTriangle[t] = f;
    for (let k = 0; k < 3; k++) {
      const v = faces.triangles[3 * t + k]!;
      const key = v * n + f;
      let w = remap.get(key);
      if (w === undefined) {
        w = source.length;
        remap.set(key, w);
        source.push(v);
        faceOfVertex.push(f);
      }
      triangles[3 * t + k] = w;
    }
  }
  const positions = new Float32Array(3 * source.length);
  source.forEach((v, w) => {
    for (let k = 0; k < 3; k++) positions[3 * w + k] = faces.positions[3 * v + k]!;
  });
  return { positions, normals: vertexNormals(positions, triangles), triangles, faceOfVertex: Uint32Array.from(faceOfVertex), faceOfTriangle };
}
