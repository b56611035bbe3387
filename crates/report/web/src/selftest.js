// What a browser test reads back from a page opened with `#selftest`: the
// errors the page raised, the requests it made, whether every plot drew,
// whether every 3D view drew something other than its background, and
// whether its animation moved between two frames. The verdict is written as
// JSON into <pre id="fistage-selftest">, where a headless browser's DOM dump
// shows it.

import { scenes } from './scene.js';

const errors = [];
window.addEventListener('error', (event) => errors.push(String(event.message)));
window.addEventListener('unhandledrejection', (event) => errors.push(String(event.reason)));
const consoleError = console.error.bind(console);
console.error = (...args) => {
  errors.push(args.map(String).join(' '));
  consoleError(...args);
};

function plotsDrawn() {
  return Array.from(document.querySelectorAll('div.plot')).map((plot) => {
    const svg = plot.querySelector('svg.main-svg');
    const marks = plot.querySelectorAll('g.trace path, g.trace rect, g.hm image, g.trace text');
    return Boolean(svg) && marks.length > 0;
  });
}

function pixels(renderer) {
  const gl = renderer.getContext();
  const width = gl.drawingBufferWidth;
  const height = gl.drawingBufferHeight;
  const data = new Uint8Array(width * height * 4);
  gl.readPixels(0, 0, width, height, gl.RGBA, gl.UNSIGNED_BYTE, data);
  return data;
}

function differingShare(a, b) {
  let differing = 0;
  for (let i = 0; i < a.length; i += 4) {
    if (a[i] !== b[i] || a[i + 1] !== b[i + 1] || a[i + 2] !== b[i + 2]) differing += 1;
  }
  return differing / (a.length / 4);
}

function notBackground(frame) {
  const blank = new Uint8Array(frame.length);
  for (let i = 0; i < frame.length; i += 4) {
    blank.set([frame[0], frame[1], frame[2], frame[3]], i);
  }
  return differingShare(frame, blank);
}

function report(verdict) {
  const holder = document.createElement('pre');
  holder.id = 'fistage-selftest';
  holder.textContent = JSON.stringify(verdict);
  document.body.appendChild(holder);
}

// Polls until every view has drawn and moved (a loaded machine draws fewer
// frames), for at most TIMEOUT_MS; then reports.
const POLL_MS = 150;
const TIMEOUT_MS = 6000;

export function runSelfTest() {
  const started = performance.now();
  const firstFrames = new Map();
  const moved = new Map();
  const poll = () => {
    scenes.forEach((scene, index) => {
      if (scene.frames < 2) return;
      const frame = pixels(scene.renderer);
      if (!firstFrames.has(index)) {
        firstFrames.set(index, frame);
      } else if (!moved.has(index)) {
        const share = differingShare(firstFrames.get(index), frame);
        if (share > 0) moved.set(index, { share, frame });
      }
    });
    const waiting = scenes.length > moved.size;
    if (waiting && performance.now() - started < TIMEOUT_MS) {
      setTimeout(poll, POLL_MS);
      return;
    }
    report({
      errors,
      requests: performance.getEntriesByType('resource').map((entry) => entry.name),
      plots: plotsDrawn(),
      views: scenes.map((scene, index) => {
        const last = moved.get(index)?.frame ?? pixels(scene.renderer);
        return {
          frames: scene.frames,
          drawn_share: notBackground(last),
          moved_share: moved.get(index)?.share ?? 0,
        };
      }),
    });
  };
  setTimeout(poll, 500);
}
