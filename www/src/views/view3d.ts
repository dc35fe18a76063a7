// The 3D view (three.js, WebGL, in the render worker): the part, optionally as the verifier's
// scallop heat map, the spiral coloured along its length, the ball-end tool at the scrubbed path
// point, and tool-axis needles for 5-axis plans. Orbit (left drag), pan (right drag), zoom
// (wheel), fit-to-part. Renders on demand only (after a change or while the camera moves).
//
// The planner worker prepares every array drawn (normals, heat colours, the path at two levels of
// detail), so nothing here walks the mesh or the whole path: the path is drawn whole near the
// part and decimated seen from afar, and the hover picks on the decimated one, then among the
// few points it stands for. The part, path and needles are drawn into a layer with its depth
// when they or the camera change; moving the tool draws that layer and the tool only.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { SURFACE } from "../lib/colors";
import type { StepDrawing } from "../lib/index";
import { DepthLayer } from "./depth-layer";
import { drawIn, type Rect } from "./dirty-rects";
import type { ElementProxy } from "./element-proxy";
import { dispose, polylineObject } from "./objects";
import { readPixels } from "./read-pixels";
import { FacesLayer } from "./faces3d";
import type { FaceState, FlankView, Layers, PartView, PathView } from "./render-protocol";

export class View3d {
  private readonly renderer: THREE.WebGLRenderer;
  private readonly scene = new THREE.Scene();
  private readonly camera = new THREE.PerspectiveCamera(35, 1, 0.1, 10000);
  private readonly controls: OrbitControls;
  private readonly content = new THREE.Group();
  private surface: THREE.Mesh<THREE.BufferGeometry, THREE.MeshStandardMaterial> | null = null;
  /** The surface's colour attribute, and its plain colours (the heat map's are the plan's). */
  private colours: THREE.BufferAttribute | null = null;
  private plainColours: Float32Array | null = null;
  private path: THREE.LOD | null = null;
  /** The decimated path (also the far level of `path`): the hover picks on it. */
  private pathCoarse: THREE.LineSegments | null = null;
  private needles: THREE.LineSegments | null = null;
  /**
   * A flank plan: its own surface (the planner's mesh, coloured by deviation) in place of the
   * part's, the tips' paths and the tool axes per strip.
   */
  private flank: { surface: THREE.Mesh<THREE.BufferGeometry, THREE.MeshStandardMaterial>; heat: Float32Array; plain: Float32Array; tips: THREE.LineSegments; axes: THREE.LineSegments; envelopes: THREE.LineSegments } | null = null;
  private readonly tool = new THREE.Group();
  /** The tool's own scene (drawn over the layer), with lights like the part's. */
  private readonly toolScene = new THREE.Scene();
  private readonly toolSun = new THREE.DirectionalLight(0xffffff, 1.6);
  private readonly layer = new DepthLayer();
  private layerStale = true;
  /** Where the last frame drew the tool (null: nowhere); undefined: the next frame draws everything. */
  private toolRect: Rect | null | undefined = undefined;
  private plan: PathView | null = null;
  /** A STEP file's faces (kept across parts of the same file), and whether the part's surface is hidden. */
  private faces: FacesLayer | null = null;
  private hideSurface = false;
  private pressedAt: [number, number] | null = null;
  private cursor = -1;
  /** Where the camera looks from when fitting (a unit vector from the part's centre). */
  private fitDirection = DEFAULT_VIEW.clone();
  /** Camera distance of the last fit: the full path is drawn nearer than half of it. */
  private fitDistance = 1;
  private layers: Layers = { heatMap: true, path: true, needles: true };
  private readonly raycaster = new THREE.Raycaster();
  private stale = true;

  /** Hover over the path: the index of the path point under the pointer. */
  onCursor: (index: number) => void = () => {};
  /** A click on a STEP face (its index in the face list). */
  onFacePick: (face: number) => void = () => {};

  constructor(
    canvas: OffscreenCanvas,
    private readonly element: ElementProxy,
    pixelRatio: number,
    private readonly requestRender: () => void,
  ) {
    // preserveDrawingBuffer: the tests read the pixels back.
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(pixelRatio);
    this.renderer.setClearColor(0xf7f8fa);
    this.camera.up.set(0, 0, 1); // machine convention: Z is the tool axis
    this.controls = new OrbitControls(this.camera, element as unknown as HTMLElement);
    this.controls.enableDamping = false;
    this.controls.addEventListener("change", () => this.invalidate(true));
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.copy(SUN);
    this.camera.add(sun); // the light follows the camera: no dark side when orbiting
    this.scene.add(this.camera, this.content);
    this.tool.visible = false;
    this.toolScene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.6), this.toolSun, this.tool);
    element.addEventListener("pointermove", (event) => {
      if ((event as PointerEvent).buttons === 0) this.hover(event as PointerEvent);
    });
    // A click that did not orbit (moved under 4 px) picks a face.
    element.addEventListener("pointerdown", (event) => (this.pressedAt = [(event as PointerEvent).clientX, (event as PointerEvent).clientY]));
    element.addEventListener("click", (event) => {
      const { clientX: x, clientY: y } = event as PointerEvent;
      const moved = this.pressedAt ? Math.hypot(x - this.pressedAt[0], y - this.pressedAt[1]) : 0;
      if (this.faces === null || moved > 4) return;
      const face = this.faces.faceAt(this.ndc(x, y), this.camera);
      if (face !== null) this.onFacePick(face);
    });
  }

  resize(width: number, height: number): void {
    this.element.clientWidth = width;
    this.element.clientHeight = height;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    const buffer = this.renderer.getDrawingBufferSize(new THREE.Vector2());
    this.layer.resize(buffer.x, buffer.y);
    this.invalidate(true);
  }

  /** Shows a newly loaded part (and forgets the previous plan). */
  setPart(part: PartView): void {
    this.clear();
    this.fitDirection = DEFAULT_VIEW.clone();
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(part.positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(part.triangles, 1));
    geometry.setAttribute("normal", new THREE.BufferAttribute(part.normals, 3));
    this.plainColours = new Float32Array(part.positions.length);
    for (let i = 0; i < this.plainColours.length; i += 3) this.plainColours.set(SURFACE, i);
    // One attribute for the part's life: the heat map is copied into it (a new attribute would
    // leave the old GPU buffer behind until the geometry goes).
    this.colours = new THREE.BufferAttribute(this.plainColours.slice(), 3);
    geometry.setAttribute("color", this.colours);
    const material = new THREE.MeshStandardMaterial({
      vertexColors: true,
      side: THREE.DoubleSide,
      roughness: 0.65,
      metalness: 0.05,
      polygonOffset: true, // the path lies on the surface: keep it in front
      polygonOffsetFactor: 1,
      polygonOffsetUnits: 1,
    });
    this.surface = new THREE.Mesh(geometry, material);
    this.surface.visible = !this.hideSurface;
    this.content.add(this.surface);
    this.fit();
    this.invalidate(true);
  }

  /** Shows a STEP file's faces (null: none, an STL part). */
  setFaces(faces: StepDrawing | null): void {
    this.faces?.dispose();
    this.faces = faces && new FacesLayer(faces);
    if (this.faces) this.scene.add(this.faces.mesh);
    this.hideSurface = false;
    if (this.surface) this.surface.visible = true;
    this.fit(DEFAULT_VIEW.clone());
  }

  /** Colours the faces by selection and leaves out those the part's surface draws. */
  setFaceState(state: FaceState): void {
    this.faces?.setState(state.selected, state.covered);
    this.hideSurface = state.hideSurface;
    if (this.surface) this.surface.visible = !state.hideSurface && this.flank === null;
    this.invalidate(true);
  }

  /** Where face `face` can be clicked (CSS pixels), or null. */
  facePoint(face: number): [number, number] | null {
    this.camera.updateMatrixWorld();
    const at = this.faces?.visiblePoint(face, this.camera);
    if (!at) return null;
    return [((at.x + 1) / 2) * this.element.clientWidth, ((1 - at.y) / 2) * this.element.clientHeight];
  }

  /** Shows a plan of the current part (or a Coons band plan on the faces): heat map, path, needles, tool. */
  setPlan(plan: PathView): void {
    this.dropFlank();
    this.plan = plan;
    dispose(this.path);
    dispose(this.needles);
    this.path = this.makePath(plan);
    this.content.add(this.path);
    this.needles = plan.fiveAxis ? this.makeNeedles(plan.pathTips, plan.pathAxes, plan.radiusMm) : null;
    if (this.needles) this.content.add(this.needles);
    this.makeTool(plan.radiusMm);
    this.applyLayers();
    this.setCursor(0);
    this.invalidate(true);
  }

  /** Shows a flank plan (and forgets a spiral plan): no tool to scrub, nothing to hover. */
  setFlank(view: FlankView): void {
    this.dropFlank();
    this.plan = null;
    this.cursor = -1;
    this.tool.visible = false;
    dispose(this.path);
    dispose(this.needles);
    this.path = this.pathCoarse = this.needles = null;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(view.positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(view.triangles, 1));
    geometry.setAttribute("normal", new THREE.BufferAttribute(view.normals, 3));
    const plain = new Float32Array(view.heat.length);
    for (let i = 0; i < plain.length; i += 3) plain.set(SURFACE, i);
    geometry.setAttribute("color", new THREE.BufferAttribute(view.heat.slice(), 3));
    const material = new THREE.MeshStandardMaterial({ vertexColors: true, side: THREE.DoubleSide, roughness: 0.65, metalness: 0.05, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
    const lines = (positions: Float32Array, colours: Float32Array) => {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(positions, 3));
      g.setAttribute("color", new THREE.BufferAttribute(colours, 3));
      return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ vertexColors: true }));
    };
    this.flank = { surface: new THREE.Mesh(geometry, material), heat: view.heat, plain, tips: lines(view.tipLines, view.tipColours), axes: lines(view.axisLines, view.axisColours), envelopes: lines(view.envelopeLines, view.envelopeColours) };
    this.content.add(this.flank.surface, this.flank.tips, this.flank.axes, this.flank.envelopes);
    if (this.surface) this.surface.visible = false;
    this.applyLayers();
    // A flank tool works beside a wall, often away from +Z: look from the side the surface
    // faces (its normals point to the tool), a little from above.
    const facing = new THREE.Vector3();
    for (let i = 0; i < view.normals.length; i += 3) facing.add(new THREE.Vector3(view.normals[i], view.normals[i + 1], view.normals[i + 2]));
    if (facing.length() > 0.2 * (view.normals.length / 3)) this.fit(facing.normalize().add(new THREE.Vector3(0.25, -0.35, 0.45)).normalize());
  }

  /** Removes a flank plan's objects and shows the part's surface again. */
  private dropFlank(): void {
    if (this.flank === null) return;
    for (const object of [this.flank.surface, this.flank.tips, this.flank.axes, this.flank.envelopes]) dispose(object);
    this.flank = null;
    if (this.surface) this.surface.visible = !this.hideSurface;
  }

  setLayers(layers: Layers): void {
    this.layers = layers;
    this.applyLayers();
  }

  /** Puts the tool at path point `index` (its toolpath move). */
  setCursor(index: number): void {
    const plan = this.plan;
    if (plan === null || plan.moveOfPoint.length === 0) return;
    this.cursor = Math.max(0, Math.min(plan.moveOfPoint.length - 1, index));
    const m = plan.moveOfPoint[this.cursor]!;
    const tip = new THREE.Vector3(plan.pathTips[3 * m], plan.pathTips[3 * m + 1], plan.pathTips[3 * m + 2]);
    const axis = new THREE.Vector3(plan.pathAxes[3 * m], plan.pathAxes[3 * m + 1], plan.pathAxes[3 * m + 2]).normalize();
    // The tool's local +Y is its axis; its origin is the tip.
    this.tool.position.copy(tip);
    this.tool.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), axis);
    this.tool.visible = true;
    this.invalidate();
  }

  /** Frames the whole part, seen from `direction` (kept for the Fit button). */
  fit(direction = this.fitDirection): void {
    this.fitDirection = direction;
    const box = this.box();
    if (box === null) return this.invalidate();
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    const distance = (sphere.radius / Math.sin(THREE.MathUtils.degToRad(this.camera.fov / 2))) * 1.05;
    this.camera.position.copy(sphere.center).addScaledVector(direction, distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(sphere.center);
    this.controls.update();
    this.fitDistance = distance;
    this.placeLevels();
    this.invalidate(true);
  }

  /** The part's box: the STEP file's faces, else the part's surface. */
  private box(): THREE.Box3 | null {
    if (this.faces) return this.faces.box();
    const geometry = this.surface?.geometry;
    if (geometry === undefined) return null;
    if (geometry.boundingBox === null) geometry.computeBoundingBox();
    return geometry.boundingBox;
  }

  private ndc(x: number, y: number): THREE.Vector2 {
    const { clientWidth: w, clientHeight: h } = this.element;
    return new THREE.Vector2((x / w) * 2 - 1, -(y / h) * 2 + 1);
  }

  /** Renders when something changed; the tool tip's place on screen (CSS pixels), if shown. */
  render(): [number, number] | null | undefined {
    if (!this.stale) return undefined;
    this.stale = false;
    const whole = this.layerStale || this.toolRect === undefined;
    if (this.layerStale) {
      this.layer.capture(this.renderer, this.scene, this.camera);
      this.layerStale = false;
    }
    this.toolSun.position.copy(this.camera.localToWorld(SUN.clone()));
    const draw = () => {
      this.layer.draw(this.renderer);
      this.renderer.autoClear = false;
      this.renderer.render(this.toolScene, this.camera);
      this.renderer.autoClear = true;
    };
    const rect = this.tool.visible ? this.toolOnScreen() : null;
    const { clientWidth: w, clientHeight: h } = this.element;
    if (whole) draw();
    else drawIn(this.renderer, [this.toolRect, rect].filter((r): r is Rect => r != null), w, h, draw);
    this.toolRect = rect;
    if (!this.tool.visible) return null;
    const p = this.tool.position.clone().project(this.camera);
    return [((p.x + 1) / 2) * this.element.clientWidth, ((1 - p.y) / 2) * this.element.clientHeight];
  }

  /** The tool's box on screen (CSS pixels, a few pixels wider); the whole canvas when it reaches behind the camera. */
  private toolOnScreen(): Rect {
    const { clientWidth: w, clientHeight: h } = this.element;
    const box = new THREE.Box3().setFromObject(this.tool);
    this.camera.updateMatrixWorld();
    let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
    const p = new THREE.Vector3();
    for (let k = 0; k < 8; k++) {
      p.set(k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y, k & 4 ? box.max.z : box.min.z).project(this.camera);
      if (p.z < -1 || p.z > 1) return { x: 0, y: 0, w, h };
      [x0, x1] = [Math.min(x0, ((p.x + 1) / 2) * w), Math.max(x1, ((p.x + 1) / 2) * w)];
      [y0, y1] = [Math.min(y0, ((1 - p.y) / 2) * h), Math.max(y1, ((1 - p.y) / 2) * h)];
    }
    return { x: x0 - 3, y: y0 - 3, w: x1 - x0 + 6, h: y1 - y0 + 6 };
  }

  /** RGBA of a region of the last frame (CSS pixels, rows top first). */
  pixels(x: number, y: number, width: number, height: number): { width: number; height: number; data: Uint8Array } {
    return readPixels(this.renderer, x, y, width, height);
  }

  /** Something changed: the tool only, or (`layer`) what the layer holds. */
  private invalidate(layer = false): void {
    this.layerStale ||= layer;
    if (layer) this.toolRect = undefined;
    this.stale = true;
    this.requestRender();
  }

  /**
   * The path point under the pointer: a pick within about one tool radius of the decimated line,
   * then the nearest to the ray of the path points that segment stands for.
   */
  private hover(event: PointerEvent): void {
    const plan = this.plan;
    if (this.path === null || this.pathCoarse === null || !this.path.visible || plan === null) return;
    this.raycaster.setFromCamera(this.ndc(event.clientX, event.clientY), this.camera);
    this.raycaster.params.Line = { threshold: plan.radiusMm };
    const hit = this.raycaster.intersectObject(this.pathCoarse)[0];
    if (hit?.index === undefined) return;
    // The hit's index is the segment's place in the index buffer: its first vertex is there.
    const { points: kept, segments } = plan.drawing.pathCoarse;
    const v = segments[hit.index]!;
    const [from, to] = [kept[Math.max(0, v - 1)]!, kept[Math.min(kept.length - 1, v + 2)]!];
    const c = plan.pathContacts;
    const point = new THREE.Vector3();
    let [best, bestD] = [from, Infinity];
    for (let i = from; i <= to; i++) {
      const d = this.raycaster.ray.distanceSqToPoint(point.set(c[3 * i]!, c[3 * i + 1]!, c[3 * i + 2]!));
      if (d < bestD) [best, bestD] = [i, d];
    }
    if (best === this.cursor) return;
    this.setCursor(best);
    this.onCursor(best);
  }

  /** The heat map's colours (or the plain ones) into the surface's colour attribute. */
  private paintHeat(): void {
    const attribute = this.colours;
    if (attribute === null || this.plainColours === null) return;
    const heat = this.plan?.drawing.heat;
    const colours = this.layers.heatMap && heat && heat.length === attribute.array.length ? heat : this.plainColours;
    (attribute.array as Float32Array).set(colours);
    attribute.needsUpdate = true;
  }

  /** The path at two levels of detail: whole near the part, decimated seen from afar. */
  private makePath(plan: PathView): THREE.LOD {
    const lod = new THREE.LOD();
    const full = polylineObject(plan.drawing.path);
    this.pathCoarse = polylineObject(plan.drawing.pathCoarse);
    for (const level of [full, this.pathCoarse]) level.frustumCulled = false;
    lod.addLevel(full, 0);
    lod.addLevel(this.pathCoarse, 1);
    this.path = lod;
    this.placeLevels();
    return lod;
  }

  /**
   * The LOD measures the camera's distance to its own position: put it at the part's centre (its
   * levels shifted back) and switch to the whole path nearer than half the fitted distance.
   */
  private placeLevels(): void {
    const lod = this.path;
    const centre = this.box()?.getCenter(new THREE.Vector3());
    if (lod === null || centre === undefined) return;
    lod.position.copy(centre);
    for (const level of lod.levels) level.object.position.copy(centre).negate();
    lod.levels[1]!.distance = 0.5 * this.fitDistance;
  }

  /** A needle along the tool axis from the tip at every k-th move (at most ~400 needles). */
  private makeNeedles(tips: Float64Array, axes: Float64Array, radius: number): THREE.LineSegments {
    const moves = tips.length / 3;
    const step = Math.max(1, Math.ceil(moves / 400));
    const points: number[] = [];
    for (let m = 0; m < moves; m += step) {
      const [x, y, z] = [tips[3 * m]!, tips[3 * m + 1]!, tips[3 * m + 2]!];
      points.push(x, y, z, x + 3 * radius * axes[3 * m]!, y + 3 * radius * axes[3 * m + 1]!, z + 3 * radius * axes[3 * m + 2]!);
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(points), 3));
    return new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color: 0x7a4fd1, transparent: true, opacity: 0.55 }));
  }

  /** Ball (centre one radius above the tip) and a shank, semi-transparent so the cut stays visible. */
  private makeTool(radius: number): void {
    for (const child of [...this.tool.children]) dispose(child);
    const material = new THREE.MeshStandardMaterial({ color: 0xc9ced6, metalness: 0.6, roughness: 0.3, transparent: true, opacity: 0.8 });
    const ball = new THREE.Mesh(new THREE.SphereGeometry(radius, 24, 16), material);
    ball.position.set(0, radius, 0);
    const shank = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 6 * radius, 24, 1, true), material);
    shank.position.set(0, radius + 3 * radius, 0);
    this.tool.add(ball, shank);
  }

  private applyLayers(): void {
    this.paintHeat();
    if (this.flank) {
      const colours = this.flank.surface.geometry.getAttribute("color") as THREE.BufferAttribute;
      (colours.array as Float32Array).set(this.layers.heatMap ? this.flank.heat : this.flank.plain);
      colours.needsUpdate = true;
      this.flank.tips.visible = this.layers.path;
      this.flank.envelopes.visible = this.layers.path;
      this.flank.axes.visible = this.layers.needles;
    }
    if (this.path) this.path.visible = this.layers.path;
    if (this.needles) this.needles.visible = this.layers.needles;
    this.invalidate(true);
  }

  private clear(): void {
    this.plan = null;
    this.cursor = -1;
    this.tool.visible = false;
    for (const child of [...this.content.children]) dispose(child);
    this.surface = this.path = this.needles = this.pathCoarse = null;
    this.flank = null;
    this.colours = this.plainColours = null;
  }
}

/** The camera's direction from the part when fitting (machine convention: from the front right, above). */
const DEFAULT_VIEW = new THREE.Vector3(0.55, -1, 0.85).normalize();

/** The light that follows the camera, in the camera's frame. */
const SUN = new THREE.Vector3(1, -2, 3);
