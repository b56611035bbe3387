// One renderer per block type: facts (key and value), table, plot (a Plotly
// figure as fistage wrote it), text, and scene (the 3D mode view).

import Plotly from 'plotly.js-cartesian-dist-min';
import { renderScene } from './scene.js';

const PLOT_CONFIG = { responsive: true, displaylogo: false, scrollZoom: false };

function cell(tag, text) {
  const node = document.createElement(tag);
  node.textContent = text;
  return node;
}

function renderFacts(block, box) {
  const table = document.createElement('table');
  table.className = 'facts';
  for (const [key, value] of block.rows) {
    const row = document.createElement('tr');
    row.appendChild(cell('th', key));
    row.appendChild(cell('td', value));
    table.appendChild(row);
  }
  box.appendChild(table);
}

function renderTable(block, box) {
  const table = document.createElement('table');
  table.className = 'grid';
  const head = document.createElement('tr');
  for (const name of block.columns) head.appendChild(cell('th', name));
  table.appendChild(head);
  for (const values of block.rows) {
    const row = document.createElement('tr');
    values.forEach((value) => row.appendChild(cell('td', value)));
    table.appendChild(row);
  }
  box.appendChild(table);
}

function renderPlot(block, box) {
  const holder = document.createElement('div');
  holder.className = 'plot';
  box.appendChild(holder);
  const layout = Object.assign(
    { margin: { l: 70, r: 20, t: 20, b: 50 }, hovermode: 'x unified', height: block.height || 360 },
    block.layout,
  );
  Plotly.newPlot(holder, block.traces, layout, PLOT_CONFIG);
}

function renderText(block, box) {
  const paragraph = cell('p', block.text);
  if (block.tone) paragraph.className = block.tone;
  box.appendChild(paragraph);
}

const RENDERERS = {
  facts: renderFacts,
  table: renderTable,
  plot: renderPlot,
  text: renderText,
  scene: (block, box) => renderScene(block, box, renderPlot),
};

export function renderBlock(block, box) {
  const render = RENDERERS[block.type];
  if (!render) throw new Error(`unknown block type ${block.type}`);
  render(block, box);
}
