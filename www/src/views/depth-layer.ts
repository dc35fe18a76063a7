// A scene rendered once into a texture with its depth, then drawn back with both each frame, so
// that small moving objects (the tool) are drawn over it with correct occlusion without drawing
// the scene again: a frame then costs a quad, whatever the part's size (software WebGL took 0.4 s
// per frame for a 300k-face part, redrawn whole for every scrub or hover).

import * as THREE from "three";

export class DepthLayer {
  private target: THREE.WebGLRenderTarget | null = null;
  private readonly quad: THREE.Mesh<THREE.PlaneGeometry, THREE.ShaderMaterial>;
  private readonly scene = new THREE.Scene();
  private readonly camera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);

  constructor() {
    const material = new THREE.ShaderMaterial({
      uniforms: { colour: { value: null }, depth: { value: null } },
      vertexShader: "varying vec2 vUv; void main() { vUv = uv; gl_Position = vec4(position.xy, 0.0, 1.0); }",
      // The colour was rendered linear into the texture: the output conversion happens here.
      fragmentShader: `uniform sampler2D colour; uniform sampler2D depth; varying vec2 vUv;
        void main() {
          gl_FragColor = texture2D(colour, vUv);
          gl_FragDepth = texture2D(depth, vUv).x;
          #include <colorspace_fragment>
        }`,
      depthTest: true, // depth is written only while the test is on: let every fragment pass
      depthFunc: THREE.AlwaysDepth,
      depthWrite: true,
    });
    this.quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), material);
    this.quad.frustumCulled = false;
    this.scene.add(this.quad);
  }

  /** The layer's size in device pixels (after the renderer's). */
  resize(width: number, height: number): void {
    this.target?.depthTexture?.dispose();
    this.target?.dispose();
    const target = new THREE.WebGLRenderTarget(width, height, { samples: 4 });
    target.depthTexture = new THREE.DepthTexture(width, height);
    this.target = target;
    this.quad.material.uniforms["colour"]!.value = target.texture;
    this.quad.material.uniforms["depth"]!.value = target.depthTexture;
  }

  /** Renders `scene` into the layer. */
  capture(renderer: THREE.WebGLRenderer, scene: THREE.Scene, camera: THREE.Camera): void {
    if (this.target === null) return;
    renderer.setRenderTarget(this.target);
    renderer.render(scene, camera);
    renderer.setRenderTarget(null);
  }

  /** Draws the layer (colour and depth) to the canvas. */
  draw(renderer: THREE.WebGLRenderer): void {
    renderer.render(this.scene, this.camera);
  }
}
