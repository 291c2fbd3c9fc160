// The parts of three.js the casmech player uses, bundled by build.sh into ../three.min.js as
// one classic script that defines the global THREE (the page stays a single offline file).
export {
  AmbientLight, BufferAttribute, BufferGeometry, Color, ConeGeometry, CylinderGeometry,
  DirectionalLight, DoubleSide, Float32BufferAttribute, GridHelper, Group, HemisphereLight,
  Line, LineBasicMaterial, LineSegments, MathUtils, Matrix4, Mesh, MeshBasicMaterial,
  MeshStandardMaterial, Object3D, PCFShadowMap, PerspectiveCamera, PlaneGeometry,
  Quaternion, SRGBColorSpace, Scene, SphereGeometry, Vector3, WebGLRenderer
} from 'three';
export { OrbitControls } from 'three/addons/controls/OrbitControls.js';
export { CSS2DObject, CSS2DRenderer } from 'three/addons/renderers/CSS2DRenderer.js';
export { toCreasedNormals } from 'three/addons/utils/BufferGeometryUtils.js';
