// The 3D mode view: the stage's bodies drawn from the shapes fistage wrote
// (URDF visuals, or each body's inertia-equivalent box), the solids welded to
// the world, the rails, and the
// isolators as lines between their attach points; the chosen mode animated
// on it. A body moves rigidly: at phase p its origin is displaced by
// s (t_re cos p - t_im sin p) and it turns by s (r_re cos p - r_im sin p)
// (a rotation vector), where t and r are the body's translation and rotation
// per unit of the mode shape and s the exaggeration.

import {
  AmbientLight, BoxGeometry, Color, CylinderGeometry, DirectionalLight, Group,
  Mesh, MeshStandardMaterial, PerspectiveCamera, Quaternion, Scene,
  SphereGeometry, Vector3, WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const COLOURS = { visual: 0x8899aa, inertia: 0x7f93b0, bearing: 0xd9822b, rail: 0x555555 };
const CYCLE_SECONDS = 2.0;
const STILL = { translation_re: [0, 0, 0], translation_im: [0, 0, 0], rotation_re: [0, 0, 0], rotation_im: [0, 0, 0] };

export const scenes = [];

function vector(values) {
  return new Vector3(values[0], values[1], values[2]);
}

function quaternion(values) {
  return new Quaternion(values[0], values[1], values[2], values[3]);
}

function geometryOf(shape) {
  if (shape.kind === 'box') return new BoxGeometry(shape.size[0], shape.size[1], shape.size[2]);
  if (shape.kind === 'sphere') return new SphereGeometry(shape.size[0], 24, 16);
  // URDF cylinders lie along their frame's z axis, three.js's along y.
  const cylinder = new CylinderGeometry(shape.size[0], shape.size[0], shape.size[1], 32);
  cylinder.rotateX(Math.PI / 2);
  return cylinder;
}

function meshOf(shape) {
  const material = new MeshStandardMaterial({
    color: COLOURS[shape.role] ?? COLOURS.visual,
    // The table sees through, so the bearings under it stay in view.
    transparent: shape.role !== 'bearing',
    opacity: shape.role === 'bearing' ? 1.0 : 0.75,
    metalness: 0.1,
    roughness: 0.7,
  });
  const mesh = new Mesh(geometryOf(shape), material);
  mesh.position.copy(vector(shape.position));
  mesh.quaternion.copy(quaternion(shape.quaternion));
  return mesh;
}

function bodyGroups(block, scene) {
  return block.bodies.map((body) => {
    const group = new Group();
    group.position.copy(vector(body.position));
    group.quaternion.copy(quaternion(body.quaternion));
    body.shapes.forEach((shape) => group.add(meshOf(shape)));
    scene.add(group);
    return group;
  });
}

function addGround(block, scene) {
  for (const shape of block.ground) scene.add(meshOf(shape));
}

function addRails(block, scene) {
  for (const rail of block.rails) {
    const start = vector(rail.start);
    const end = vector(rail.end);
    const length = start.distanceTo(end);
    const width = block.span * 0.02;
    const mesh = new Mesh(
      new BoxGeometry(length, width, width),
      new MeshStandardMaterial({ color: COLOURS.rail }),
    );
    mesh.position.copy(start.clone().add(end).multiplyScalar(0.5));
    mesh.quaternion.setFromUnitVectors(new Vector3(1, 0, 0), end.clone().sub(start).normalize());
    scene.add(mesh);
  }
}

// An isolator is drawn as a green strut from its child body's origin to its
// attach point on the parent, with a ball at the attach point: the two ends
// move with their bodies, so the strut shows the isolator's deflection.
function isolatorStruts(block, scene) {
  const material = new MeshStandardMaterial({ color: 0x1a9850 });
  const radius = block.span * 0.006;
  return block.isolators.map((isolator) => {
    const strut = new Mesh(new CylinderGeometry(radius, radius, 1, 12), material);
    const ball = new Mesh(new SphereGeometry(radius * 2.5, 16, 12), material);
    scene.add(strut, ball);
    return { isolator, strut, ball };
  });
}

function worldPoint(groups, body, point) {
  const local = vector(point);
  return body < 0 ? local : groups[body].localToWorld(local);
}

function updateIsolators(groups, struts) {
  for (const { isolator, strut, ball } of struts) {
    const a = worldPoint(groups, isolator.parent, isolator.parent_point);
    const b = isolator.child < 0
      ? vector(isolator.child_point)
      : groups[isolator.child].localToWorld(new Vector3());
    const along = b.clone().sub(a);
    const length = Math.max(along.length(), 1e-9);
    strut.position.copy(a.clone().add(b).multiplyScalar(0.5));
    strut.scale.set(1, length, 1);
    strut.quaternion.setFromUnitVectors(new Vector3(0, 1, 0), along.normalize());
    ball.position.copy(a);
  }
}

// Poses of every body at phase `phase` of `mode`, exaggerated by `scale`.
function pose(block, groups, mode, phase, scale) {
  const c = Math.cos(phase) * scale;
  const s = Math.sin(phase) * scale;
  block.bodies.forEach((body, index) => {
    const motion = mode.bodies[index];
    const t = vector(motion.translation_re).multiplyScalar(c)
      .add(vector(motion.translation_im).multiplyScalar(-s));
    const r = vector(motion.rotation_re).multiplyScalar(c)
      .add(vector(motion.rotation_im).multiplyScalar(-s));
    const angle = r.length();
    const turn = angle > 0 ? new Quaternion().setFromAxisAngle(r.normalize(), angle) : new Quaternion();
    groups[index].position.copy(vector(body.position).add(t));
    groups[index].quaternion.copy(turn.multiply(quaternion(body.quaternion)));
    groups[index].updateMatrixWorld(true);
  });
}

function modeLabel(mode) {
  const marker = mode.unstable ? 'UNSTABLE ' : '';
  return `${marker}${mode.label}: ${mode.frequency_hz.toPrecision(4)} Hz, zeta ${mode.damping_ratio.toPrecision(3)}`;
}

function controls(block, box) {
  const bar = document.createElement('div');
  bar.className = 'scene-controls';
  const select = document.createElement('select');
  block.modes.forEach((mode, index) => {
    const option = document.createElement('option');
    option.value = String(index);
    option.textContent = modeLabel(mode);
    if (mode.unstable) option.className = 'unstable';
    select.appendChild(option);
  });
  const slider = document.createElement('input');
  Object.assign(slider, { type: 'range', min: '0', max: '5', step: '0.05', value: '1' });
  const play = document.createElement('input');
  Object.assign(play, { type: 'checkbox', checked: true });
  const label = (text, input) => {
    const node = document.createElement('label');
    node.append(text, input);
    return node;
  };
  bar.append(label('mode ', select), label(' exaggeration ', slider), label(' animate ', play));
  box.appendChild(bar);
  return { select, slider, play };
}

function energyPlot(mode) {
  const names = mode.participation.map((p) => p.coordinate);
  return {
    type: 'plot',
    height: 260,
    traces: [{
      type: 'bar',
      x: names,
      y: mode.participation.map((p) => p.share),
      customdata: mode.participation.map((p) => [p.magnitude, p.phase_deg]),
      hovertemplate: '%{x}: share %{y:.3f}, magnitude %{customdata[0]:.3f}, phase %{customdata[1]:.1f} deg<extra></extra>',
      marker: { color: mode.participation.map((p) => (Math.abs(p.phase_deg) > 90 ? '#d73027' : '#4575b4')) },
    }],
    layout: { yaxis: { title: { text: 'kinetic-energy share' }, range: [0, 1] }, hovermode: 'closest', margin: { l: 60, r: 10, t: 10, b: 80 } },
  };
}

export function renderScene(block, box, renderPlot) {
  const { select, slider, play } = controls(block, box);
  const info = document.createElement('p');
  info.className = 'scene-info';
  box.appendChild(info);
  const canvasBox = document.createElement('div');
  canvasBox.className = 'scene-canvas';
  box.appendChild(canvasBox);
  const energyBox = document.createElement('div');
  box.appendChild(energyBox);

  const width = canvasBox.clientWidth || 800;
  const height = 460;
  const renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  canvasBox.appendChild(renderer.domElement);
  const scene = new Scene();
  scene.background = new Color(0xf7f7f7);
  scene.add(new AmbientLight(0xffffff, 1.2));
  const sun = new DirectionalLight(0xffffff, 2.0);
  sun.position.set(1, -1, 2);
  scene.add(sun);
  const span = block.span;
  const centre = vector(block.centre);
  const camera = new PerspectiveCamera(40, width / height, span * 0.01, span * 100);
  camera.up.set(0, 0, 1);
  camera.position.copy(centre.clone().add(new Vector3(0.75 * span, -1.1 * span, 0.8 * span)));
  const orbit = new OrbitControls(camera, renderer.domElement);
  orbit.target.copy(centre);
  orbit.update();

  const groups = bodyGroups(block, scene);
  addRails(block, scene);
  addGround(block, scene);
  const lines = isolatorStruts(block, scene);
  const state = { mode: 0, started: performance.now() };
  const explain = () => {
    const mode = block.modes[state.mode];
    if (!mode) {
      info.textContent = 'no mode with mechanical content to animate';
      return;
    }
    info.textContent = `${modeLabel(mode)}; ${mode.equilibrium} equilibrium; ${mode.summary}`;
    info.classList.toggle('unstable', mode.unstable);
    energyBox.replaceChildren();
    renderPlot(energyPlot(mode), energyBox);
  };
  select.addEventListener('change', () => { state.mode = Number(select.value); explain(); });
  explain();

  const draw = () => {
    const mode = block.modes[state.mode] ?? { bodies: block.bodies.map(() => STILL), scale: 0 };
    const seconds = (performance.now() - state.started) / 1000;
    const phase = play.checked ? (2 * Math.PI * seconds) / CYCLE_SECONDS : 0;
    pose(block, groups, mode, phase, Number(slider.value) * mode.scale);
    updateIsolators(groups, lines);
    renderer.render(scene, camera);
    view.frames += 1;
  };
  const view = { renderer, draw, frames: 0 };
  scenes.push(view);
  renderer.setAnimationLoop(draw);
}
