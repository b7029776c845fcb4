// lightpath view: the page. Plain JS, no build step. It asks the server for what it
// shows (thumbnails, the AOV in the large view, the mixer's parts) as half floats,
// draws the large view with WebGL2 (a CPU fallback when there is none) and thumbnails
// on 2D canvases. `window.lpv` exposes the state and a few hooks for the browser test.
'use strict';

const MAX_GROUPS = 15;
const $ = (id) => document.getElementById(id);
const lpv = (window.lpv = {
  ready: false,
  info: null,
  renderer: null,
  timings: { script: performance.now() }, // ms since the navigation started
  view: { name: null, exposure: 0, srgb: true, channel: 'rgb', noisy: false },
  mixer: null, // { base, groups: [{ part, group, arg, gain, tint }] }
});

// ---------- half floats ----------
const HALF = new Float32Array(65536);
for (let h = 0; h < 65536; h++) {
  const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 0x1f, m = h & 0x3ff;
  HALF[h] = e === 0 ? s * m * 2 ** -24 : e === 31 ? (m ? NaN : s * Infinity) : s * (1 + m / 1024) * 2 ** (e - 15);
}
const decode = (u16) => { const f = new Float32Array(u16.length); for (let i = 0; i < u16.length; i++) f[i] = HALF[u16[i]]; return f; };

// ---------- server ----------
function setStatus(text, error) {
  const s = $('status'); s.textContent = text || ''; s.classList.toggle('error', !!error);
}
async function getJSON(path) {
  const r = await fetch(path);
  const body = await r.json();
  if (!r.ok) throw new Error(body.error || r.statusText);
  return body;
}
const images = new Map(); // "name@width" → Promise<{ w, h, ch, half: Uint16Array }>
function image(name, width) {
  const key = `${name}@${width || 'full'}`;
  if (!images.has(key)) {
    const q = `/api/image?name=${encodeURIComponent(name)}` + (width ? `&width=${width}` : '');
    images.set(key, fetch(q).then(async (r) => {
      if (!r.ok) throw new Error((await r.json()).error);
      const buf = await r.arrayBuffer();
      return { w: +r.headers.get('X-Width'), h: +r.headers.get('X-Height'),
        ch: +r.headers.get('X-Channels'), half: new Uint16Array(buf) };
    }));
    images.get(key).catch(() => images.delete(key));
  }
  return images.get(key);
}

// ---------- the display transform (the shader below does the same) ----------
const srgb = (v) => (v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055);
// Allocates nothing: it runs for every pixel of every thumbnail (and of the CPU view).
const encode = (v) => {
  const x = Math.min(Math.max(v, 0), 1);
  return Math.round((lpv.view.srgb ? srgb(x) : x) * 255);
};
function display(r, g, b, out, o) {
  const k = 2 ** lpv.view.exposure;
  r *= k; g *= k; b *= k;
  const c = lpv.view.channel;
  if (c === 'r') g = b = r; else if (c === 'g') r = b = g; else if (c === 'b') r = g = b;
  else if (c === 'lum') r = g = b = 0.2126 * r + 0.7152 * g + 0.0722 * b;
  out[o] = encode(r); out[o + 1] = encode(g); out[o + 2] = encode(b);
  out[o + 3] = 255;
}

// ---------- the large view ----------
// Sizes a view's canvas for an image of w × h: shown as large as fits in the viewer
// (never enlarged), with as many pixels as it is shown with (`reduce`, on the GPU) or
// the image's own. Returns the canvas's pixel size; `.size` keeps the image's.
function fit(canvas, w, h, reduce) {
  // The viewer's width less its padding and room for a scroll bar that may appear.
  const room = $('viewer').clientWidth - 40, tall = 0.62 * window.innerHeight;
  const s = Math.min(1, room / w, tall / h);
  canvas.style.width = `${w * s}px`; canvas.style.height = `${h * s}px`;
  const k = reduce ? Math.min(1, s * (window.devicePixelRatio || 1)) : 1;
  const cw = Math.max(1, Math.round(w * k)), ch = Math.max(1, Math.round(h * k));
  if (canvas.width !== cw || canvas.height !== ch) { canvas.width = cw; canvas.height = ch; }
  lpv.renderer.size = [w, h];
  return [cw, ch];
}
const VERT = `#version 300 es
in vec2 p; void main() { gl_Position = vec4(p, 0.0, 1.0); }`;
const FRAG = `#version 300 es
precision highp float; precision highp int; precision highp sampler2DArray;
uniform sampler2DArray img; uniform int n; uniform vec3 gain[${MAX_GROUPS}];
uniform float scale; uniform int channel; uniform bool encode; uniform ivec2 size; uniform vec2 ratio;
out vec4 color;
float srgb(float v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055; }
void main() {
  // The image pixel under this canvas pixel's centre (rows top down).
  ivec2 p = ivec2(gl_FragCoord.x * ratio.x, float(size.y) - gl_FragCoord.y * ratio.y);
  p = clamp(p, ivec2(0), size - 1);
  vec3 c = texelFetch(img, ivec3(p, 0), 0).rgb;
  for (int i = 0; i < ${MAX_GROUPS}; i++) {
    if (i >= n) break;
    c += (gain[i] - 1.0) * texelFetch(img, ivec3(p, i + 1), 0).rgb;
  }
  c *= scale;
  if (channel == 1) c = c.rrr; else if (channel == 2) c = c.ggg; else if (channel == 3) c = c.bbb;
  else if (channel == 4) c = vec3(dot(c, vec3(0.2126, 0.7152, 0.0722)));
  c = clamp(c, 0.0, 1.0);
  if (encode) c = vec3(srgb(c.r), srgb(c.g), srgb(c.b));
  color = vec4(c, 1.0);
}`;

class GpuView {
  constructor(canvas) {
    const gl = canvas.getContext('webgl2', { preserveDrawingBuffer: true, antialias: false, premultipliedAlpha: false });
    if (!gl) throw new Error('no WebGL2');
    const sh = (type, src) => {
      const s = gl.createShader(type); gl.shaderSource(s, src); gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      return s;
    };
    const prog = gl.createProgram();
    gl.attachShader(prog, sh(gl.VERTEX_SHADER, VERT));
    gl.attachShader(prog, sh(gl.FRAGMENT_SHADER, FRAG));
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(prog));
    gl.useProgram(prog);
    gl.bindBuffer(gl.ARRAY_BUFFER, gl.createBuffer());
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
    const loc = gl.getAttribLocation(prog, 'p');
    gl.enableVertexAttribArray(loc);
    gl.vertexAttribPointer(loc, 2, gl.FLOAT, false, 0, 0);
    this.u = {};
    for (const k of ['img', 'n', 'gain', 'scale', 'channel', 'encode', 'size', 'ratio']) this.u[k] = gl.getUniformLocation(prog, k);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    this.gl = gl; this.canvas = canvas; this.tex = null; this.layers = [];
    this.name = 'WebGL2';
  }
  // layers: [base, part1, …] images of one size; uploaded only when they change, as RGBA
  // (RGB16F textures are converted to RGBA by the driver, slowly: 4× the time in
  // SwiftShader, and ANGLE on Direct3D does the same).
  draw(layers, gains) {
    const gl = this.gl, base = layers[0];
    if (this.layers.length !== layers.length || this.layers.some((l, i) => l !== layers[i])) {
      if (this.tex) gl.deleteTexture(this.tex);
      this.tex = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D_ARRAY, this.tex);
      gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, gl.RGBA16F, base.w, base.h, layers.length);
      const n = base.w * base.h;
      if (!this.rgba || this.rgba.length !== 4 * n) this.rgba = new Uint16Array(4 * n).fill(0x3c00);
      const rgba = this.rgba;
      for (const [i, l] of layers.entries()) {
        const h = l.half;
        for (let k = 0, j = 0; k < 3 * n; k += 3, j += 4) { rgba[j] = h[k]; rgba[j + 1] = h[k + 1]; rgba[j + 2] = h[k + 2]; }
        gl.texSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, i, l.w, l.h, 1, gl.RGBA, gl.HALF_FLOAT, rgba);
      }
      this.layers = layers.slice();
    }
    // The canvas has the pixels it is shown with (no more than the image's): a 1080p AOV
    // in a 900-pixel-wide view is sampled at 900 × 506, not drawn at 1920 × 1080.
    const [cw, ch] = fit(this.canvas, base.w, base.h, true);
    gl.viewport(0, 0, cw, ch);
    const g = new Float32Array(3 * MAX_GROUPS);
    gains.forEach((v, i) => g.set(v, 3 * i));
    gl.uniform1i(this.u.img, 0);
    gl.uniform1i(this.u.n, layers.length - 1);
    gl.uniform3fv(this.u.gain, g);
    gl.uniform1f(this.u.scale, 2 ** lpv.view.exposure);
    gl.uniform1i(this.u.channel, ['rgb', 'r', 'g', 'b', 'lum'].indexOf(lpv.view.channel));
    gl.uniform1i(this.u.encode, lpv.view.srgb ? 1 : 0);
    gl.uniform2i(this.u.size, base.w, base.h);
    gl.uniform2f(this.u.ratio, base.w / cw, base.h / ch);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }
  // The shown pixel at image pixel (x, y) (itself when the view is not reduced).
  readPixel(x, y) {
    const out = new Uint8Array(4), c = this.canvas, [w, h] = this.size;
    const cx = Math.min(c.width - 1, Math.floor(((x + 0.5) * c.width) / w));
    const cy = Math.min(c.height - 1, Math.floor(((y + 0.5) * c.height) / h));
    this.gl.readPixels(cx, c.height - 1 - cy, 1, 1, this.gl.RGBA, this.gl.UNSIGNED_BYTE, out);
    return Array.from(out);
  }
}

class CpuView {
  constructor(canvas) { this.canvas = canvas; this.ctx = canvas.getContext('2d'); this.name = 'CPU'; this.floats = new WeakMap(); }
  f(img) { if (!this.floats.has(img)) this.floats.set(img, decode(img.half)); return this.floats.get(img); }
  draw(layers, gains) {
    const base = layers[0], n = base.w * base.h;
    const planes = layers.map((l) => this.f(l));
    fit(this.canvas, base.w, base.h, false);
    const out = this.ctx.createImageData(base.w, base.h);
    for (let i = 0; i < n; i++) {
      let r = planes[0][3 * i], g = planes[0][3 * i + 1], b = planes[0][3 * i + 2];
      for (let k = 1; k < planes.length; k++) {
        const p = planes[k], s = gains[k - 1];
        r += (s[0] - 1) * p[3 * i]; g += (s[1] - 1) * p[3 * i + 1]; b += (s[2] - 1) * p[3 * i + 2];
      }
      display(r, g, b, out.data, 4 * i);
    }
    this.ctx.putImageData(out, 0, 0);
  }
  readPixel(x, y) { return Array.from(this.ctx.getImageData(x, y, 1, 1).data); }
}

// ---------- AOV list ----------
const shownName = (name) => {
  const twin = lpv.info.noisy.find((t) => t.aov === name);
  return lpv.view.noisy && twin ? twin.noisy : name;
};

function card(name, definition, kind) {
  const el = document.createElement('div');
  el.className = 'card';
  el.dataset[kind] = name;
  el.title = definition;
  const twin = lpv.info.noisy.find((t) => t.aov === name);
  if (twin) el.dataset.noisy = twin.noisy;
  el.innerHTML = '<canvas></canvas><div class="name"></div><div class="expr"></div>';
  el.querySelector('.name').textContent = name + (twin ? ' (+ _noisy)' : '');
  el.querySelector('.expr').textContent = definition;
  el.addEventListener('click', () => select(name));
  return el;
}

function section(parent, title, check) {
  const s = document.createElement('section');
  s.className = 'partition';
  const h = document.createElement('h3');
  h.textContent = title;
  if (check !== undefined) {
    const c = document.createElement('span');
    const ok = check !== null && check <= lpv.info.tolerance;
    c.className = 'check ' + (check === null ? '' : ok ? 'ok' : 'bad');
    c.textContent = check === null ? ' · not measured yet' : ` · max error ${check.toExponential(2)} ${ok ? '✓' : '✗'}`;
    h.appendChild(c);
  }
  const cards = document.createElement('div');
  cards.className = 'cards';
  s.append(h, cards);
  parent.appendChild(s);
  return cards;
}

function buildList() {
  const info = lpv.info, nav = $('aovs');
  nav.textContent = '';
  const twins = new Set(info.noisy.map((t) => t.noisy));
  const defs = new Map(info.aovs.map((a) => [a.name, a.definition]));
  const placed = new Set();
  const kinds = { standard: 'standard set', bounces: 'bounces', lightgroups: 'light groups' };
  const others = info.aovs.filter((a) => !a.partition && !twins.has(a.name) && a.present);
  others.sort((a, b) => (b.name === info.beauty) - (a.name === info.beauty));
  const main = section(nav, 'AOVs');
  for (const a of others) { main.appendChild(card(a.name, a.definition, 'aov')); placed.add(a.name); }
  for (const p of info.partitions) {
    const title = `${kinds[p.kind] || p.kind}: ${p.whole} = ${p.parts.join(' + ')}`;
    const cards = section(nav, title, p.max_relative_error);
    cards.parentElement.dataset.partition = `${p.whole}/${p.kind}`;
    for (const name of p.parts) {
      if (twins.has(name) || !defs.has(name)) continue;
      cards.appendChild(card(name, defs.get(name), 'aov'));
      placed.add(name);
    }
  }
  if (info.cryptomatte.length) {
    const cards = section(nav, 'Cryptomatte (click the image to pick an object)');
    for (const l of info.cryptomatte) cards.appendChild(card(l.name, `${l.objects} objects, ${l.ranks} ranks`, 'crypto'));
  }
  $('noisy-toggle').hidden = info.noisy.length === 0;
  return Promise.all([...nav.querySelectorAll('.card')].map(drawThumb));
}

async function drawThumb(el) {
  const name = shownName(el.dataset.aov || el.dataset.crypto);
  const img = await image(name, lpv.info.thumbnail_width);
  const c = el.querySelector('canvas');
  c.width = img.w; c.height = img.h;
  const ctx = c.getContext('2d'), out = ctx.createImageData(img.w, img.h);
  for (let i = 0; i < img.w * img.h; i++) {
    display(HALF[img.half[3 * i]], HALF[img.half[3 * i + 1]], HALF[img.half[3 * i + 2]], out.data, 4 * i);
  }
  ctx.putImageData(out, 0, 0);
}
const redrawThumbs = () => Promise.all([...document.querySelectorAll('.card')].map(drawThumb));

// ---------- selection, mixer ----------
function isCrypto(name) { return lpv.info.cryptomatte.some((l) => l.name === name); }

async function select(name) {
  lpv.view.name = name;
  for (const el of document.querySelectorAll('.card')) el.classList.toggle('selected', (el.dataset.aov || el.dataset.crypto) === name);
  await drawView();
}

const fmt = (x) => String(parseFloat(x.toFixed(4)));
const tintRGB = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255);

// The --gain arguments of the current sliders (groups left at gain 1, white, omitted).
function gainArgs() {
  if (!lpv.mixer) return [];
  return lpv.mixer.groups.flatMap((g) => {
    const t = tintRGB(g.tint);
    if (t.every((v) => v === 1)) return g.gain === 1 ? [] : [`${g.arg}=${fmt(g.gain)}`];
    return [`${g.arg}=${t.map((v) => fmt(g.gain * v)).join(',')}`];
  });
}
// The gains the view applies: the arguments' numbers, so the view is what a save writes.
function gainsOf(args) {
  const byArg = new Map(args.map((a) => { const [k, v] = a.split('='); const n = v.split(',').map(Number); return [k, n.length === 1 ? [n[0], n[0], n[0]] : n]; }));
  return lpv.mixer.groups.map((g) => byArg.get(g.arg) || [1, 1, 1]);
}

function buildMixer() {
  const m = lpv.info.mixers[0];
  $('mixer').hidden = !m;
  $('no-mixer').hidden = !!m;
  if (!m) { lpv.mixer = null; return; }
  const groups = m.groups.slice(0, MAX_GROUPS);
  const keep = lpv.mixer && lpv.mixer.base === m.base ? new Map(lpv.mixer.groups.map((g) => [g.part, g])) : new Map();
  lpv.mixer = { base: m.base, groups: groups.map((g) => keep.get(g.part) || { ...g, gain: 1, tint: '#ffffff' }) };
  $('mixer-base').textContent = m.base;
  const caveat = lpv.info.relight_caveat;
  $('relight-caveat').hidden = !caveat;
  $('relight-caveat').textContent = caveat ? `Relighting this file is not a re-render: it was ${caveat}.` : '';
  const box = $('groups');
  box.textContent = '';
  for (const g of lpv.mixer.groups) {
    const row = document.createElement('div');
    row.className = 'group';
    row.dataset.group = g.arg;
    row.innerHTML = '<label></label><input type="range" min="0" max="4" step="0.01"><output></output><input type="color"><button type="button" title="reset">↺</button>';
    const [label, slider, out, tint, reset] = row.children;
    label.textContent = g.group;
    label.title = g.part;
    slider.value = g.gain; out.textContent = fmt(g.gain); tint.value = g.tint;
    slider.addEventListener('input', () => { g.gain = +slider.value; out.textContent = fmt(g.gain); mixChanged(); });
    tint.addEventListener('input', () => { g.tint = tint.value; mixChanged(); });
    reset.addEventListener('click', () => { g.gain = 1; g.tint = '#ffffff'; slider.value = 1; out.textContent = '1'; tint.value = g.tint; mixChanged(); });
    box.appendChild(row);
  }
  const stem = lpv.info.title.replace(/\.exr$/i, '');
  if (!$('comp-name').value) $('comp-name').value = `${stem}_comp.exr`;
}

function mixChanged() {
  $('command').textContent = ''; // the saved comp's command line no longer matches the view
  if (lpv.view.name !== lpv.mixer.base || lpv.view.noisy) { lpv.view.noisy = false; $('noisy').checked = false; select(lpv.mixer.base); return; }
  drawView();
}

let drawing = Promise.resolve();
function drawView() {
  drawing = drawing.then(drawViewNow, drawViewNow);
  return drawing;
}
async function drawViewNow() {
  const name = lpv.view.name;
  if (!name) return;
  const shown = isCrypto(name) ? name : shownName(name);
  const t0 = performance.now();
  const base = await image(shown, 0);
  const t1 = performance.now();
  let layers = [base], gains = [];
  const mixing = lpv.mixer && name === lpv.mixer.base && shown === name;
  const args = mixing ? gainArgs() : [];
  if (mixing && (args.length || lpv.mixer.loaded)) {
    // The parts are fetched the first time a slider moves, then kept on the GPU.
    layers = [base, ...(await Promise.all(lpv.mixer.groups.map((g) => image(g.part, 0))))];
    gains = gainsOf(args);
    lpv.mixer.loaded = true;
  }
  const t2 = performance.now();
  lpv.renderer.draw(layers, gains);
  lpv.timings.view = { fetch: t1 - t0, parts: t2 - t1, draw: performance.now() - t2 };
  $('current').textContent = shown + (args.length ? ` with ${args.join(' ')}` : '');
  const def = lpv.info.aovs.find((a) => a.name === shown);
  $('current').title = def ? def.definition : '';
  lpv.drawn = { name: shown, args };
}

// ---------- pixel inspector, Cryptomatte ----------
function imageXY(ev) {
  const r = $('view').getBoundingClientRect(), [w, h] = lpv.renderer.size || [0, 0];
  const x = Math.floor(((ev.clientX - r.left) / r.width) * w);
  const y = Math.floor(((ev.clientY - r.top) / r.height) * h);
  return x >= 0 && y >= 0 && x < w && y < h ? [x, y] : null;
}
let inspecting = false, pendingXY = null;
async function inspect(xy) {
  if (inspecting) { pendingXY = xy; return; }
  inspecting = true;
  try {
    const p = await getJSON(`/api/pixel?x=${xy[0]}&y=${xy[1]}`);
    $('pixel-at').textContent = `(${p.x}, ${p.y})` + (p.alpha === null ? '' : ` alpha ${p.alpha.toPrecision(4)}`);
    const body = $('pixel').tBodies[0];
    body.textContent = '';
    for (const v of p.values) {
      const tr = body.insertRow();
      tr.dataset.aov = v.name;
      if (v.name === lpv.drawn?.name) tr.className = 'selected';
      tr.insertCell().textContent = v.name;
      for (const c of v.rgb) tr.insertCell().textContent = c.toPrecision(4);
    }
    for (const o of p.cryptomatte) {
      const tr = body.insertRow();
      tr.insertCell().textContent = o.layer;
      const td = tr.insertCell(); td.colSpan = 3; td.textContent = `${o.name ?? '?'} (${o.id}, ${o.coverage.toPrecision(3)})`;
    }
  } catch (e) { setStatus(e.message, true); }
  inspecting = false;
  if (pendingXY) { const next = pendingXY; pendingXY = null; inspect(next); }
}

async function pick(xy) {
  if (!lpv.info.cryptomatte.length) return;
  // The layer shown, else objects (CryptoObject) before materials and assets.
  const layers = lpv.info.cryptomatte;
  const layer = isCrypto(lpv.view.name) ? lpv.view.name : (layers.find((l) => /object/i.test(l.name)) || layers[0]).name;
  const p = await getJSON(`/api/pixel?x=${xy[0]}&y=${xy[1]}`);
  const o = p.cryptomatte.find((c) => c.layer === layer);
  const overlay = $('matte');
  const ctx = overlay.getContext('2d');
  if (!o) { ctx.clearRect(0, 0, overlay.width, overlay.height); $('object').textContent = ''; lpv.picked = null; return; }
  const m = await fetchMatte(layer, o.id);
  overlay.width = m.w; overlay.height = m.h;
  const out = ctx.createImageData(m.w, m.h);
  for (let i = 0; i < m.w * m.h; i++) {
    const a = Math.min(Math.max(HALF[m.half[i]], 0), 1);
    out.data.set([255, 190, 60, Math.round(170 * a)], 4 * i);
  }
  ctx.putImageData(out, 0, 0);
  $('object').textContent = `${layer}: ${o.name ?? 'object not in the manifest'} (id ${o.id})`;
  lpv.picked = { layer, ...o, matte: m };
}

async function fetchMatte(layer, id) {
  const r = await fetch(`/api/matte?layer=${encodeURIComponent(layer)}&id=${id}`);
  if (!r.ok) throw new Error((await r.json()).error);
  return { w: +r.headers.get('X-Width'), h: +r.headers.get('X-Height'), half: new Uint16Array(await r.arrayBuffer()) };
}

// ---------- save comp ----------
async function saveComp() {
  const body = { gains: gainArgs(), base: lpv.mixer.base, output: $('comp-name').value.trim(), exposure: lpv.view.exposure };
  setStatus('saving…');
  try {
    const r = await fetch('/api/comp', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
    const a = await r.json();
    if (!r.ok) throw new Error(a.error);
    $('command').textContent = a.command;
    setStatus(`wrote ${a.output} and ${a.png}`);
    lpv.saved = a;
  } catch (e) { setStatus(e.message, true); lpv.saved = { error: e.message }; }
}

// ---------- live renders, checks still being measured ----------
const waiting = (i) => i.live || !i.comp || i.partitions.some((p) => p.max_relative_error === null);
async function poll() {
  try {
    const info = await getJSON('/api/info');
    const checks = (i) => JSON.stringify(i.partitions.map((p) => p.max_relative_error));
    if (info.generation === lpv.info.generation && info.live === lpv.info.live && checks(info) !== checks(lpv.info)) {
      lpv.info = info;
      await buildList(); // the partition checks arrived
      for (const el of document.querySelectorAll('.card')) el.classList.toggle('selected', (el.dataset.aov || el.dataset.crypto) === lpv.view.name);
    } else if (info.generation !== lpv.info.generation || info.live !== lpv.info.live) {
      images.clear();
      const structure = info.live !== lpv.info.live;
      lpv.info = info;
      showSummary();
      if (structure) { await buildList(); buildMixer(); } else await redrawThumbs();
      if (lpv.mixer) lpv.mixer.loaded = false;
      await drawView();
    }
    if (waiting(info)) setTimeout(poll, 1000);
  } catch (e) { setStatus(`lost the server: ${e.message}`, true); }
}

function showSummary() {
  const i = lpv.info;
  document.title = `${i.title} — lightpath view`;
  $('title').textContent = i.title;
  $('summary').textContent = `${i.width}×${i.height}, ${i.aovs.length} AOVs` + (i.live ? ' · rendering…' : '');
  $('save-comp').disabled = !i.comp;
}

// ---------- start ----------
async function main() {
  lpv.image = image;
  const canvas = $('view');
  const forceCpu = new URLSearchParams(location.search).has('cpu');
  try { lpv.renderer = forceCpu ? new CpuView(canvas) : new GpuView(canvas); } catch (e) { lpv.renderer = new CpuView(canvas); lpv.gpuError = e.message; }
  $('renderer').textContent = `drawn with ${lpv.renderer.name}`;
  lpv.info = await getJSON('/api/info');
  lpv.timings.info = performance.now();
  showSummary();
  buildMixer();
  const first = lpv.info.aovs.some((a) => a.name === lpv.info.beauty) ? lpv.info.beauty : lpv.info.aovs[0]?.name;
  if (first) image(first, 0); // asked for before the thumbnails: the view is what is looked at
  const thumbs = buildList();
  if (first) { await select(first); lpv.timings.beauty = performance.now(); }
  await thumbs;
  lpv.timings.thumbnails = performance.now();

  $('exposure').addEventListener('input', () => { lpv.view.exposure = +$('exposure').value; $('exposure-value').textContent = lpv.view.exposure.toFixed(1); drawView(); redrawThumbs(); });
  $('srgb').addEventListener('change', () => { lpv.view.srgb = $('srgb').checked; drawView(); redrawThumbs(); });
  $('channel').addEventListener('change', () => { lpv.view.channel = $('channel').value; drawView(); redrawThumbs(); });
  $('noisy').addEventListener('change', () => { lpv.view.noisy = $('noisy').checked; drawView(); redrawThumbs(); });
  $('save-comp').addEventListener('click', saveComp);
  window.addEventListener('resize', () => drawView());
  $('reset').addEventListener('click', () => { for (const g of lpv.mixer.groups) { g.gain = 1; g.tint = '#ffffff'; } buildMixer(); mixChanged(); });
  canvas.addEventListener('mousemove', (ev) => { const xy = imageXY(ev); if (xy) inspect(xy); });
  canvas.addEventListener('click', (ev) => { const xy = imageXY(ev); if (xy) pick(xy).catch((e) => setStatus(e.message, true)); });
  lpv.readPixel = (x, y) => lpv.renderer.readPixel(x, y);
  lpv.idle = () => drawing;
  lpv.ready = true;
  if (waiting(lpv.info)) setTimeout(poll, 1000);
}

main().catch((e) => { setStatus(e.message, true); lpv.error = e.message; });
