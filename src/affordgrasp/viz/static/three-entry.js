// Entry of the vendored three.js bundle (three.bundle.min.js): only what viewer.js uses.
// Rebuild with build-three.sh (npm; three and esbuild at the versions pinned there).
export {
  ArrowHelper,
  BufferAttribute,
  BufferGeometry,
  ConeGeometry,
  DirectionalLight,
  Group,
  HemisphereLight,
  Line,
  LineDashedMaterial,
  Mesh,
  MeshBasicMaterial,
  MeshLambertMaterial,
  PerspectiveCamera,
  Scene,
  SphereGeometry,
  Vector3,
  WebGLRenderer,
} from "three";
export { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
