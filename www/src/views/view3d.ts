// The 3D view (three.js, WebGL): the part, optionally as the verifier's scallop heat map, the
// spiral coloured along its length, the ball-end tool at the scrubbed path point, and tool-axis
// needles for 5-axis plans. Orbit (left drag), pan (right drag), zoom (wheel), fit-to-part.
// Renders on demand only (after a change or while the camera moves).

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import type { LoadedPart, PlanResult } from "../lib/index";
import { SURFACE, heatColour, pathColour } from "./colors";

export interface View3dLayers {
  heatMap: boolean;
  path: boolean;
  needles: boolean;
}

export class View3d {
  private readonly renderer: THREE.WebGLRenderer;
  private readonly scene = new THREE.Scene();
  private readonly camera = new THREE.PerspectiveCamera(35, 1, 0.1, 10000);
  private readonly controls: OrbitControls;
  private readonly content = new THREE.Group();
  private surface: THREE.Mesh<THREE.BufferGeometry, THREE.MeshStandardMaterial> | null = null;
  private path: THREE.Line | null = null;
  private needles: THREE.LineSegments | null = null;
  private readonly tool = new THREE.Group();
  private plan: PlanResult | null = null;
  /** Scallop limit h the heat map is scaled to, mm. */
  private limit = 0.02;
  /** Ball radius of the plan shown, mm. */
  private radius = 3;
  private layers: View3dLayers = { heatMap: true, path: true, needles: true };
  private frame = 0;
  private readonly raycaster = new THREE.Raycaster();

  /** Hover over the path: the index of the path point under the pointer. */
  onCursor: (index: number) => void = () => {};

  constructor(private readonly canvas: HTMLCanvasElement) {
    // preserveDrawingBuffer: the tests (and screenshots) read the pixels back.
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio));
    this.renderer.setClearColor(0xf7f8fa);
    this.camera.up.set(0, 0, 1); // machine convention: Z is the tool axis
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = false;
    this.controls.addEventListener("change", () => this.requestRender());
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(1, -2, 3);
    this.camera.add(sun); // the light follows the camera: no dark side when orbiting
    this.scene.add(this.camera, this.content);
    this.tool.visible = false;
    this.scene.add(this.tool);
    canvas.addEventListener("pointermove", (event) => {
      if (event.buttons === 0) this.hover(event);
    });
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  /** The path point under the pointer (a pick within about one tool radius of the line). */
  private hover(event: PointerEvent): void {
    if (this.path === null || !this.path.visible || this.plan === null) return;
    const rect = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1, -((event.clientY - rect.top) / rect.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    this.raycaster.params.Line = { threshold: this.radius };
    const hit = this.raycaster.intersectObject(this.path)[0];
    if (hit?.index === undefined) return;
    this.setCursor(hit.index);
    this.onCursor(hit.index);
  }

  /** Shows a newly loaded part (and forgets the previous plan). */
  setPart(part: LoadedPart): void {
    this.clear();
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(part.positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(part.triangles, 1));
    geometry.computeVertexNormals();
    const colours = new Float32Array(part.positions.length);
    for (let i = 0; i < colours.length; i += 3) colours.set(SURFACE, i);
    geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
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
    this.content.add(this.surface);
    this.fit();
  }

  /** Shows a plan of the current part: heat map, path, needles, tool. */
  setPlan(plan: PlanResult, radiusMm: number, scallopMm: number, fiveAxis: boolean): void {
    this.plan = plan;
    this.limit = scallopMm;
    this.radius = radiusMm;
    this.disposeObject(this.path);
    this.disposeObject(this.needles);
    this.path = this.needles = null;
    this.path = this.makePath(plan.pathContacts);
    this.content.add(this.path);
    if (fiveAxis) {
      this.needles = this.makeNeedles(plan.pathTips, plan.pathAxes, radiusMm);
      this.content.add(this.needles);
    }
    this.makeTool(radiusMm);
    this.applyLayers();
    this.setCursor(0);
  }

  setLayers(layers: View3dLayers): void {
    this.layers = layers;
    this.applyLayers();
  }

  /** Puts the tool at path point `index` (its toolpath move). */
  setCursor(index: number): void {
    const plan = this.plan;
    if (plan === null || plan.moveOfPoint.length === 0) return;
    const i = Math.max(0, Math.min(plan.moveOfPoint.length - 1, index));
    const m = plan.moveOfPoint[i]!;
    const tip = new THREE.Vector3(plan.pathTips[3 * m], plan.pathTips[3 * m + 1], plan.pathTips[3 * m + 2]);
    const axis = new THREE.Vector3(plan.pathAxes[3 * m], plan.pathAxes[3 * m + 1], plan.pathAxes[3 * m + 2]).normalize();
    // The tool's local +Y is its axis; its origin is the tip.
    this.tool.position.copy(tip);
    this.tool.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), axis);
    this.tool.visible = true;
    this.requestRender();
  }

  /** Frames the whole part. */
  fit(): void {
    const box = new THREE.Box3().setFromObject(this.content);
    if (box.isEmpty()) return this.requestRender();
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    const distance = sphere.radius / Math.sin(THREE.MathUtils.degToRad(this.camera.fov / 2)) * 1.05;
    const direction = new THREE.Vector3(0.55, -1, 0.85).normalize();
    this.camera.position.copy(sphere.center).addScaledVector(direction, distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(sphere.center);
    this.controls.update();
    this.requestRender();
  }

  private paintHeat(scallop: Float64Array, limit: number): void {
    const surface = this.surface;
    if (surface === null) return;
    const attribute = surface.geometry.getAttribute("color") as THREE.BufferAttribute;
    const colours = attribute.array as Float32Array;
    const heat = this.layers.heatMap && scallop.length * 3 === colours.length;
    for (let v = 0; v < colours.length / 3; v++) colours.set(heat ? heatColour(scallop[v]!, limit) : SURFACE, 3 * v);
    attribute.needsUpdate = true;
  }

  private makePath(contacts: Float64Array): THREE.Line {
    const n = contacts.length / 3;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(contacts), 3));
    const colours = new Float32Array(contacts.length);
    for (let i = 0; i < n; i++) colours.set(pathColour(n > 1 ? i / (n - 1) : 0), 3 * i);
    geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
    return new THREE.Line(geometry, new THREE.LineBasicMaterial({ vertexColors: true }));
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
    for (const child of [...this.tool.children]) this.disposeObject(child);
    const material = new THREE.MeshStandardMaterial({ color: 0xc9ced6, metalness: 0.6, roughness: 0.3, transparent: true, opacity: 0.8 });
    const ball = new THREE.Mesh(new THREE.SphereGeometry(radius, 24, 16), material);
    ball.position.set(0, radius, 0);
    const shank = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 6 * radius, 24, 1, true), material);
    shank.position.set(0, radius + 3 * radius, 0);
    this.tool.add(ball, shank);
  }

  private applyLayers(): void {
    if (this.plan !== null) this.paintHeat(this.plan.vertexScallop, this.limit);
    if (this.path) this.path.visible = this.layers.path;
    if (this.needles) this.needles.visible = this.layers.needles;
    this.requestRender();
  }

  private clear(): void {
    this.plan = null;
    this.tool.visible = false;
    for (const child of [...this.content.children]) this.disposeObject(child);
    this.surface = this.path = this.needles = null;
  }

  private disposeObject(object: THREE.Object3D | null): void {
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

  private resize(): void {
    const { clientWidth: w, clientHeight: h } = this.canvas;
    if (w === 0 || h === 0) return;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  private requestRender(): void {
    if (this.frame !== 0) return;
    this.frame = requestAnimationFrame(() => {
      this.frame = 0;
      this.renderer.render(this.scene, this.camera);
    });
  }
}
