#include "app/report/report_page.h"

namespace modestack::app::report {

const char* page_style()
{
    return R"CSS(
body { font-family: sans-serif; margin: 16px 24px; color: #222; background: #fafafa; max-width: 1500px; }
h1 { font-size: 20px; margin-bottom: 4px; } h2 { font-size: 16px; margin: 22px 0 6px; border-bottom: 1px solid #ccc; }
code, .mono { font-family: monospace; font-size: 12px; word-break: break-all; }
.note { color: #555; font-size: 13px; margin: 2px 0; } .reasoning { font-size: 14px; }
.row { display: flex; flex-wrap: wrap; gap: 10px; align-items: flex-start; }
.panel { display: flex; flex-direction: column; font-size: 12px; }
.viewport { position: relative; overflow: hidden; background: #000; cursor: grab; border: 1px solid #888; }
.viewport canvas { position: absolute; left: 0; top: 0; image-rendering: pixelated; transform-origin: 0 0; }
.modes img { width: 160px; image-rendering: pixelated; border: 1px solid #888; display: block; }
.modes figure { margin: 0; font-size: 11px; }
table { border-collapse: collapse; font-size: 13px; } td, th { border: 1px solid #ccc; padding: 3px 8px; text-align: left; }
#rank-canvas { width: 640px; image-rendering: pixelated; border: 1px solid #888; background: #000; }
.controls { margin: 6px 0; font-size: 13px; } .controls input[type=range] { width: 320px; vertical-align: middle; }
)CSS";
}

const char* page_script()
{
    return R"JS(
'use strict';
const data = JSON.parse(document.getElementById('report-data').textContent);
let exposure = 0;
const views = [];     // {canvas, pixels: Float32Array (rgb), width, height, offset (stops), mask}
let rankPreview = null;

function decode(uri) {
  return new Promise((resolve, reject) => {
    const image = new Image();
    image.onload = () => {
      const canvas = document.createElement('canvas');
      canvas.width = image.width; canvas.height = image.height;
      const context = canvas.getContext('2d');
      context.drawImage(image, 0, 0);
      resolve(context.getImageData(0, 0, image.width, image.height));
    };
    image.onerror = () => reject(new Error('an embedded image failed to decode'));
    image.src = uri;
  });
}

// RGBA bytes -> Float32 RGB through a 256-entry table.
function toFloat(imageData, table) {
  const n = imageData.width * imageData.height, out = new Float32Array(n * 3), bytes = imageData.data;
  for (let i = 0; i < n; ++i)
    for (let c = 0; c < 3; ++c) out[i * 3 + c] = table[bytes[i * 4 + c]];
  return out;
}
function logTable(low, high) {
  const table = new Float32Array(256);
  for (let q = 1; q < 256; ++q) table[q] = Math.pow(2, low + q / 255 * (high - low));
  return table;
}
function linearTable(offset, scale) {
  const table = new Float32Array(256);
  for (let q = 0; q < 256; ++q) table[q] = offset + scale * q;
  return table;
}
function srgb(v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055; }

// Scene-linear RGB -> the canvas, after the exposure (stops); alpha stays 255.
function paint(canvas, pixels, width, height, stops, mask) {
  const context = canvas.getContext('2d'), out = context.createImageData(width, height), gain = Math.pow(2, stops);
  for (let i = 0, n = width * height; i < n; ++i) {
    for (let c = 0; c < 3; ++c) {
      const v = mask ? pixels[i * 3 + c] : pixels[i * 3 + c] * gain;
      out.data[i * 4 + c] = Math.round(255 * srgb(Math.min(1, Math.max(0, v))));
    }
    out.data[i * 4 + 3] = 255;
  }
  context.putImageData(out, 0, 0);
}

function repaintAll() {
  for (const view of views) paint(view.canvas, view.pixels, view.width, view.height, exposure + view.offset, view.mask);
  if (rankPreview) drawRank();
  document.getElementById('exposure-value').textContent = (exposure >= 0 ? '+' : '') + exposure.toFixed(1) + ' stops';
}

// Synchronised zoom and pan: one state for every viewport (image-relative).
const zoom = {scale: 1, x: 0, y: 0};
const viewports = [];
function applyZoom() {
  for (const viewport of viewports) {
    const canvas = viewport.firstChild, width = viewport.clientWidth;
    const pixel = width / canvas.width * zoom.scale;
    canvas.style.transform = 'translate(' + (-zoom.x * pixel) + 'px,' + (-zoom.y * pixel) + 'px) scale(' + pixel + ')';
  }
  document.getElementById('zoom-value').textContent = zoom.scale.toFixed(2) + 'x';
}
function clampZoom(canvas) {
  zoom.scale = Math.min(64, Math.max(1, zoom.scale));
  zoom.x = Math.min(canvas.width * (1 - 1 / zoom.scale), Math.max(0, zoom.x));
  zoom.y = Math.min(canvas.height * (1 - 1 / zoom.scale), Math.max(0, zoom.y));
}
function addViewport(viewport) {
  viewports.push(viewport);
  viewport.addEventListener('wheel', event => {
    event.preventDefault();
    const canvas = viewport.firstChild, rect = viewport.getBoundingClientRect();
    const pixel = rect.width / canvas.width * zoom.scale;
    const pointX = zoom.x + (event.clientX - rect.left) / pixel, pointY = zoom.y + (event.clientY - rect.top) / pixel;
    zoom.scale *= event.deltaY < 0 ? 1.25 : 0.8;
    clampZoom(canvas);
    const newPixel = rect.width / canvas.width * zoom.scale;
    zoom.x = pointX - (event.clientX - rect.left) / newPixel; zoom.y = pointY - (event.clientY - rect.top) / newPixel;
    clampZoom(canvas); applyZoom();
  }, {passive: false});
  let drag = null;
  viewport.addEventListener('mousedown', event => { drag = {x: event.clientX, y: event.clientY, zx: zoom.x, zy: zoom.y}; });
  window.addEventListener('mouseup', () => { drag = null; });
  window.addEventListener('mousemove', event => {
    if (!drag) return;
    const canvas = viewport.firstChild, pixel = viewport.clientWidth / canvas.width * zoom.scale;
    zoom.x = drag.zx - (event.clientX - drag.x) / pixel; zoom.y = drag.zy - (event.clientY - drag.y) / pixel;
    clampZoom(canvas); applyZoom();
  });
}
function setZoom(scale) {
  const canvas = viewports.length ? viewports[0].firstChild : null;
  if (!canvas) return;
  const centerX = zoom.x + canvas.width / zoom.scale / 2, centerY = zoom.y + canvas.height / zoom.scale / 2;
  zoom.scale = scale;
  zoom.x = centerX - canvas.width / scale / 2; zoom.y = centerY - canvas.height / scale / 2;
  clampZoom(canvas); applyZoom();
}

// Rank slider: rebuild of the chosen frame from its segment's first n coefficient images.
function drawRank() {
  const frame = data.frames[rankPreview.frame], segment = rankPreview.segments[frame.segment];
  const slider = document.getElementById('rank-slider'), n = Math.min(+slider.value, segment.modes.length);
  const local = frame.index - data.segments[frame.segment].first, weights = data.segments[frame.segment].weights;
  const size = segment.modes[0].length, sum = new Float32Array(size);
  for (let j = 0; j < n; ++j) {
    const w = weights[j][local], mode = segment.modes[j];
    for (let i = 0; i < size; ++i) sum[i] += w * mode[i];
  }
  paint(document.getElementById('rank-canvas'), sum, segment.width, segment.height, exposure, false);
  const chosen = data.segments[frame.segment].rank;
  document.getElementById('rank-value').textContent =
    'n = ' + n + ' of ' + segment.modes.length + (n === chosen ? ' (the chosen N)' : ' (chosen N = ' + chosen + ')');
}

async function start() {
  const firstDenoised = data.frames.length ? data.frames[0].panels.find(p => p.label === 'denoised') : null;
  exposure = firstDenoised ? Math.round(-(firstDenoised.high - 2) * 2) / 2 : 0;
  const exposureSlider = document.getElementById('exposure');
  exposureSlider.min = exposure - 10; exposureSlider.max = exposure + 10; exposureSlider.value = exposure;
  exposureSlider.addEventListener('input', () => { exposure = +exposureSlider.value; repaintAll(); });

  const frameRows = document.getElementById('frames');
  for (const frame of data.frames) {
    const title = document.createElement('div');
    title.textContent = 'frame ' + frame.number;
    title.className = 'note';
    frameRows.appendChild(title);
    const row = document.createElement('div');
    row.className = 'row';
    frameRows.appendChild(row);
    const reference = frame.panels.find(p => p.label === 'denoised') || frame.panels[0];
    for (const panel of frame.panels) {
      const imageData = await decode(panel.uri);
      const canvas = document.createElement('canvas');
      canvas.width = imageData.width; canvas.height = imageData.height;
      const mask = panel.absolute;
      const offset = panel.label === 'sigma' ? Math.round((reference.high - panel.high) * 2) / 2 : 0;
      views.push({canvas, pixels: toFloat(imageData, logTable(panel.low, panel.high)), width: imageData.width,
                  height: imageData.height, offset, mask});
      const box = document.createElement('div');
      box.className = 'panel';
      const viewport = document.createElement('div');
      viewport.className = 'viewport';
      viewport.style.width = data.panelWidth + 'px';
      viewport.style.height = Math.round(data.panelWidth * imageData.height / imageData.width) + 'px';
      viewport.appendChild(canvas);
      box.appendChild(viewport);
      const label = document.createElement('span');
      label.textContent = panel.label + (offset ? ' (shown ' + (offset > 0 ? '+' : '') + offset + ' stops brighter)' : '');
      box.appendChild(label);
      row.appendChild(box);
      addViewport(viewport);
    }
  }

  // Rank slider: decode every segment's coefficient images once.
  const segments = [];
  const thumbnails = document.getElementById('modes');
  for (let s = 0; s < data.segments.length; ++s) {
    const segment = {modes: [], width: 0, height: 0};
    for (let j = 0; j < data.segments[s].modes.length; ++j) {
      const mode = data.segments[s].modes[j], imageData = await decode(mode.uri);
      segment.width = imageData.width; segment.height = imageData.height;
      segment.modes.push(toFloat(imageData, linearTable(mode.offset, mode.scale)));
      const figure = document.createElement('figure'), image = document.createElement('img');
      image.src = mode.uri;
      const caption = document.createElement('figcaption');
      caption.textContent = (data.segments.length > 1 ? 'part ' + (s + 1) + ', ' : '') + 'mode ' + (j + 1) +
                            (j < data.segments[s].rank ? '' : ' (not kept)');
      figure.appendChild(image); figure.appendChild(caption); thumbnails.appendChild(figure);
    }
    segments.push(segment);
  }
  const slider = document.getElementById('rank-slider'), picker = document.getElementById('rank-frame');
  if (data.frames.length && segments.length && segments[0].modes.length) {
    rankPreview = {frame: 0, segments};
    const canvas = document.getElementById('rank-canvas');
    canvas.width = segments[0].width; canvas.height = segments[0].height;
    data.frames.forEach((frame, k) => {
      const option = document.createElement('option');
      option.value = k; option.textContent = 'frame ' + frame.number;
      picker.appendChild(option);
    });
    const first = data.segments[data.frames[0].segment];
    slider.min = 1; slider.max = first.modes.length; slider.value = first.rank;
    slider.addEventListener('input', drawRank);
    picker.addEventListener('change', () => {
      rankPreview.frame = +picker.value;
      const segment = data.segments[data.frames[rankPreview.frame].segment];
      slider.max = segment.modes.length;
      drawRank();
    });
  }
  document.getElementById('zoom-fit').addEventListener('click', () => setZoom(1));
  document.getElementById('zoom-2').addEventListener('click', () => setZoom(2 * zoom.scale));
  document.getElementById('zoom-half').addEventListener('click', () => setZoom(zoom.scale / 2));
  repaintAll();
  applyZoom();
  window.reportReady = true;
}

start().catch(error => {
  window.reportFailure = String(error);
  console.error('report: ' + error);
});
)JS";
}

}  // namespace modestack::app::report
