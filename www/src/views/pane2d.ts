// One pane of the 2D view as three.js objects in the pane's own plane coordinates (uv or w): the
// domain's triangles filled, its boundary loops (outer dark, holes or slits red), the rings and
// the path coloured along its length. The view places the group on screen.

import * as THREE from "three";
import type { Polyline } from "../lib/index";
import { rawColour } from "./raw-colour";

const FILL = rawColour(0xdde3ec);
const OUTER = rawColour(0x1d2330);
const HOLE = rawColour(0xb42318);
const RING = rawColour(0x1f6feb);

/** Drawn in this order, without depth (a plane). */
enum Order {
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

  /** The domain: xyz (z = 0) per vertex, the triangles, and the loops' edges (vertex pairs). */
  setDomain(positions: Float32Array | null, triangles: Uint32Array, outerEdges: Uint32Array, holeEdges: Uint32Array): void {
    this.domain.forEach(dispose);
    this.domain = [];
    if (positions === null) return;
    const position = new THREE.BufferAttribute(positions, 3);
    const fill = new THREE.Mesh(geometry(position, triangles), new THREE.MeshBasicMaterial({ color: FILL, side: THREE.DoubleSide }));
    const outer = new THREE.LineSegments(geometry(position, outerEdges), new THREE.LineBasicMaterial({ color: OUTER }));
    const holes = new THREE.LineSegments(geometry(position, holeEdges), new THREE.LineBasicMaterial({ color: HOLE }));
    this.domain = [place(fill, Order.Fill), place(outer, Order.Loops), place(holes, Order.Loops)];
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

/** A polyline (see lib/drawing) as line segments with a colour per vertex. */
export function polylineObject(p: Polyline): THREE.LineSegments {
  const g = geometry(new THREE.BufferAttribute(p.positions, 3), p.segments);
  g.setAttribute("color", new THREE.BufferAttribute(p.colours, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ vertexColors: true }));
}

function geometry(position: THREE.BufferAttribute, index: Uint32Array): THREE.BufferGeometry {
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", position);
  g.setIndex(new THREE.BufferAttribute(index, 1));
  return g;
}

function place<T extends THREE.Object3D>(object: T, order: Order): T {
  object.renderOrder = order;
  object.frustumCulled = false; // the pane shows its whole domain: no bounding spheres to compute
  const material = (object as unknown as { material: THREE.Material }).material;
  material.depthTest = false;
  material.depthWrite = false;
  return object;
}

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
