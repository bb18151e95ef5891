// Entry point of the vendored bundle: the whole three.js namespace plus OrbitControls as
// `window.THREE`, so that crates/report/assets/viewer.js stays a small hand-written classic
// script and this bundle changes only when three is upgraded (see build.sh).
import * as THREE_NS from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

window.THREE = Object.assign({}, THREE_NS, { OrbitControls });
