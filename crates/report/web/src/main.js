// The report's script: reads the page's data (a JSON block written by
// fistage) and renders each section's blocks with the embedded libraries.
// Plots are Plotly figures whose traces and layout fistage wrote; the mode
// view is a three.js scene (scene.js). With `#selftest` in the address the
// page checks what it rendered (selftest.js) and writes the verdict into it.

import { renderBlock } from './blocks.js';
import { runSelfTest } from './selftest.js';

function pageData() {
  const holder = document.getElementById('fistage-report-data');
  return JSON.parse(holder.textContent);
}

function element(tag, className, text) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  if (text !== undefined) node.textContent = text;
  return node;
}

function renderSection(section, index, root) {
  const holder = element('section', 'section');
  holder.id = `section-${index}`;
  holder.appendChild(element('h2', null, section.heading));
  if (section.source) holder.appendChild(element('p', 'source', section.source));
  root.appendChild(holder);
  for (const block of section.blocks) {
    const box = element('div', `block block-${block.type}`);
    if (block.title) box.appendChild(element('h3', null, block.title));
    holder.appendChild(box);
    renderBlock(block, box);
  }
}

function renderContents(data, root) {
  if (data.sections.length < 2) return;
  const nav = element('nav', 'contents');
  data.sections.forEach((section, index) => {
    const link = element('a', null, section.heading);
    link.href = `#section-${index}`;
    nav.appendChild(link);
  });
  root.appendChild(nav);
}

function main() {
  const data = pageData();
  const root = document.getElementById('fistage-report');
  root.appendChild(element('h1', null, data.title));
  root.appendChild(element('p', 'generator', data.generator));
  renderContents(data, root);
  data.sections.forEach((section, index) => renderSection(section, index, root));
  if (window.location.hash === '#selftest') runSelfTest();
}

window.addEventListener('DOMContentLoaded', main);
