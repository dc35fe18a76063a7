// One pane of the 2D view as three.js objects in the pane's own plane coordinates (uv or w): the
// domain filled, its boundary loops (outer dark, holes or slits red), the rings and the path
// coloured along its length. The view places the group on screen.
//
// The fill is drawn from the loops alone, even-odd through the stencil buffer (a fan of triangles
// from one vertex over every boundary edge inverts the stencil bit, then a quad fills where it is
// set and clears it): a few thousand triangles instead of every face. Filling the faces of a
// 300k-face part took software WebGL 5.6 s for the two panes.

import * as THREE from "three";
import type { Polyline } from "../lib/index";
import { dispose, geometry, polylineObject } from "./objects";
import { rawColour } from "./raw-colour";

const FILL = rawColour(0xdde3ec);
const OUTER = rawColour(0x1d2330);
const HOLE = rawColour(0xb42318);
const RING = rawColour(0x1f6feb);

/** Drawn in this order, without depth (a plane). */
enum Order {
  Stencil,
  Fill,
  Loops,
  Rings,
  Path,
}

export class Pane2d {
  readonly group = new THREE.Group();
  private domain: THREE.Object3D[] = [];
  private rings: THREE.LineSegments | null = null;
  private path: THREE.LineSegments | null = null;

  /** The domain: xyz (z = 0) per vertex, and its loops' edges (vertex pairs): the outer loop's, the holes'. */
  setDomain(positions: Float32Array | null, outerEdges: Uint32Array, holeEdges: Uint32Array): void {
    this.domain.forEach(dispose);
    this.domain = [];
    if (positions === null || outerEdges.length === 0) return;
    const position = new THREE.BufferAttribute(positions, 3);
    const outer = new THREE.LineSegments(geometry(position, outerEdges), new THREE.LineBasicMaterial({ color: OUTER }));
    const holes = new THREE.LineSegments(geometry(position, holeEdges), new THREE.LineBasicMaterial({ color: HOLE }));
    this.domain = [...fill(position, [outerEdges, holeEdges]), place(outer, Order.Loops), place(holes, Order.Loops)];
    this.group.add(...this.domain);
  }

  /** The rings as line segments (xyz pairs), or none. */
  setRings(segments: Float32Array | null): void {
    dispose(this.rings);
    this.rings = null;
    if (segments === null) return;
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(segments, 3));
    const material = new THREE.LineBasicMaterial({ color: RING, transparent: true, opacity: 0.35 });
    this.rings = place(new THREE.LineSegments(g, material), Order.Rings);
    this.group.add(this.rings);
  }

  setPath(path: Polyline | null): void {
    dispose(this.path);
    this.path = null;
    if (path === null) return;
    this.path = place(polylineObject(path), Order.Path);
    this.group.add(this.path);
  }
}

/** The even-odd fill of the region the loop edges bound: the stencil fan, then the quad. */
function fill(position: THREE.BufferAttribute, edgeLists: Uint32Array[]): THREE.Mesh[] {
  const edges = edgeLists.reduce((n, e) => n + e.length / 2, 0);
  const fan = new Uint32Array(3 * edges);
  const apex = edgeLists[0]![0]!;
  let k = 0;
  for (const list of edgeLists) {
    for (let e = 0; e < list.length; e += 2) [fan[k++], fan[k++], fan[k++]] = [apex, list[e]!, list[e + 1]!];
  }
  const invert = new THREE.MeshBasicMaterial({
    colorWrite: false,
    side: THREE.DoubleSide,
    stencilWrite: true,
    stencilFunc: THREE.AlwaysStencilFunc,
    stencilZPass: THREE.InvertStencilOp,
    stencilWriteMask: 1,
  });
  const paint = new THREE.MeshBasicMaterial({
    color: FILL,
    side: THREE.DoubleSide,
    stencilWrite: true,
    stencilRef: 1,
    stencilFuncMask: 1,
    stencilFunc: THREE.EqualStencilFunc,
    stencilZPass: THREE.ZeroStencilOp, // cleared for the other pane
  });
  // The quad: the bounding box of the loops' vertices.
  const box = new THREE.Box3();
  const v = new THREE.Vector3();
  for (const list of edgeLists) for (const i of list) box.expandByPoint(v.fromBufferAttribute(position, i));
  const quad = new THREE.PlaneGeometry(1, 1);
  quad.scale(box.max.x - box.min.x, box.max.y - box.min.y, 1).translate((box.min.x + box.max.x) / 2, (box.min.y + box.max.y) / 2, 0);
  return [place(new THREE.Mesh(geometry(position, fan), invert), Order.Stencil), place(new THREE.Mesh(quad, paint), Order.Fill)];
}

function place<T extends THREE.Object3D>(object: T, order: Order): T {
  object.renderOrder = order;
  object.frustumCulled = false; // the pane shows its whole domain: no bounding spheres to compute
  const material = (object as unknown as { material: THREE.Material }).material;
  material.depthTest = false;
  material.depthWrite = false;
  return object;
}
