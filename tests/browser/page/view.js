// Renders the GLB named by ?glb= once, as a web viewer would, and leaves window.result for the test:
//   ok, error, what the file declares per primitive (its attributes, and those inside the
//   KHR_draco_mesh_compression extension), what three.js made of it (geometry attributes, whether the
//   material ended up flat-shaded), the WebGL renderer, and two RGBA frames read back with readPixels:
//   `shaded` (the picture) and `mask` (the same view, every mesh plain white on black: the silhouette).
// Query: glb=URL, size=pixels (512), material=standard|file. `standard` (the default) puts one grey
// MeshStandardMaterial (metalness 0, roughness 0.6) on every mesh so that figures from different files
// compare; it keeps what GLTFLoader decided about normals: a primitive without NORMAL is flat-shaded
// (glTF 2.0 spec, 3.7.2.1: "When normals are not specified, client implementations MUST calculate
// flat normals"; three.js does it with flatShading = true, i.e. screen-space derivatives). `file`
// keeps the file's own material (GLTFLoader's default is metalness 1, dark without an environment).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';

const q = new URLSearchParams(location.search);
const size = Number(q.get('size') || 512);
const materialMode = q.get('material') || 'standard';

function base64(bytes) {
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  return btoa(s);
}

function read(renderer) {
  const gl = renderer.getContext();
  const px = new Uint8Array(size * size * 4);
  gl.readPixels(0, 0, size, size, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const flipped = new Uint8Array(px.length);  // readPixels is bottom-up; the screenshot is top-down
  for (let y = 0; y < size; y++) flipped.set(px.subarray((size - 1 - y) * size * 4, (size - y) * size * 4), y * size * 4);
  return base64(flipped);
}

async function main() {
  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(size, size);
  renderer.setClearColor(0x000000, 1);
  document.body.appendChild(renderer.domElement);
  const gl = renderer.getContext();
  const dbg = gl.getExtension('WEBGL_debug_renderer_info');
  const glRenderer = dbg ? gl.getParameter(dbg.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);

  const draco = new DRACOLoader();
  draco.setDecoderPath('/modules/three/examples/jsm/libs/draco/gltf/');
  const loader = new GLTFLoader();
  loader.setDRACOLoader(draco);
  const gltf = await loader.loadAsync(q.get('glb'));

  const json = gltf.parser.json;
  const filePrimitives = [];
  for (const m of json.meshes || [])
    for (const p of m.primitives) {
      const ext = (p.extensions || {}).KHR_draco_mesh_compression;
      filePrimitives.push({ attributes: Object.keys(p.attributes || {}),
                            draco: ext ? Object.keys(ext.attributes || {}) : null, material: p.material ?? null });
    }

  const scene = new THREE.Scene();
  scene.add(gltf.scene);
  const loaded = [];
  const grey = (flat) => new THREE.MeshStandardMaterial({ color: 0xb3b3b3, metalness: 0, roughness: 0.6, flatShading: flat });
  gltf.scene.traverse((o) => {
    if (!o.isMesh) return;
    const flat = o.geometry.attributes.normal === undefined;
    loaded.push({ attributes: Object.keys(o.geometry.attributes), flatShading: !!o.material.flatShading,
                  vertices: o.geometry.attributes.position.count,
                  triangles: o.geometry.index ? o.geometry.index.count / 3 : o.geometry.attributes.position.count / 3 });
    if (materialMode === 'standard') o.material = grey(flat);
  });

  // Frame the bounding box's centre and the farthest vertex from it (tighter than the box's sphere).
  const box = new THREE.Box3().setFromObject(gltf.scene);
  const sphere = new THREE.Sphere(box.getCenter(new THREE.Vector3()), 0);
  const v = new THREE.Vector3();
  gltf.scene.updateMatrixWorld(true);
  gltf.scene.traverse((o) => {
    if (!o.isMesh) return;
    const p = o.geometry.attributes.position;
    for (let i = 0; i < p.count; i++)
      sphere.radius = Math.max(sphere.radius, v.fromBufferAttribute(p, i).applyMatrix4(o.matrixWorld).distanceTo(sphere.center));
  });
  const camera = new THREE.PerspectiveCamera(30, 1, sphere.radius * 0.05, sphere.radius * 10);
  const dist = sphere.radius / Math.sin(THREE.MathUtils.degToRad(15)) * 1.05;
  camera.position.copy(sphere.center).add(new THREE.Vector3(0, 0, dist));
  camera.lookAt(sphere.center);
  scene.add(new THREE.AmbientLight(0xffffff, 0.4));
  const sun = new THREE.DirectionalLight(0xffffff, 2.5);
  sun.position.copy(sphere.center).add(new THREE.Vector3(-0.5, 0.7, 1).multiplyScalar(sphere.radius * 4));
  sun.target.position.copy(sphere.center);
  scene.add(sun, sun.target);

  scene.overrideMaterial = new THREE.MeshBasicMaterial({ color: 0xffffff });
  renderer.render(scene, camera);
  const mask = read(renderer);
  scene.overrideMaterial = null;
  renderer.render(scene, camera);
  const shaded = read(renderer);
  return { ok: true, glRenderer, size, materialMode, filePrimitives, loaded, shaded, mask };
}

main().then((r) => { window.result = r; }, (e) => { window.result = { ok: false, error: String(e && e.stack || e) }; })
  .finally(() => { document.title = 'done'; });
