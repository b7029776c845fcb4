// The viewer's page in a real headless browser (Debian's chromium), driven over the
// DevTools protocol on a pipe: no npm packages. It renders a small known file, starts
// `lightpath view` on it and checks that
//   - the AOV list shows every AOV of the file with its expression (as `lightpath aovs`
//     lists them) and every partition with its measured error;
//   - moving a light-group slider (and a tint) changes the pixels as the arithmetic says
//     (base + (gain − 1)·part, from the server's float values), on WebGL2 and on the CPU
//     fallback;
//   - the pixel inspector shows every AOV;
//   - "Save comp" writes the same file as the `lightpath comp` command line it shows.
// Usage: node tests/browser/view.mjs
//        node tests/browser/view.mjs --perf FILE.exr                (timings on a file)
//        node tests/browser/view.mjs --screenshots DIR [--exr FILE]  (docs/aovs.md's pictures:
//          view-overview.png, view-mixer.png, view-inspector.png; without --exr it renders
//          the built-in cornell with light groups and Cryptomatte, 640x480 at --spp N, 64)
// Env: LIGHTPATH (the binary, default target/debug/lightpath), CHROMIUM (/usr/bin/chromium).
import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const args = process.argv.slice(2);
const opt = (name) => { const i = args.indexOf(name); return i >= 0 ? args[i + 1] : null; };
const bin = path.resolve(process.env.LIGHTPATH || 'target/debug/lightpath');
const chromium = process.env.CHROMIUM || '/usr/bin/chromium';
const shots = opt('--screenshots') && path.resolve(opt('--screenshots'));
const perf = opt('--perf') && path.resolve(opt('--perf'));
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'lightpath-view-'));
const children = [];
let browserCdp = null;
let passed = 0, failed = 0;
function check(ok, what) {
  if (ok) passed++; else failed++;
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
}
// Ends the browser and the viewer, waits for them, removes the scratch folder.
async function cleanup() {
  if (browserCdp) await Promise.race([browserCdp.send('Browser.close'), new Promise((r) => setTimeout(r, 3000))]).catch(() => {});
  await Promise.all(children.map((c) => new Promise((resolve) => {
    if (c.exitCode !== null || c.signalCode !== null) return resolve();
    c.once('exit', resolve);
    c.kill('SIGKILL');
  })));
  try { fs.rmSync(tmp, { recursive: true, force: true, maxRetries: 5, retryDelay: 200 }); } catch (e) { console.log(`(could not remove ${tmp}: ${e.message})`); }
}
const timeout = setTimeout(() => { console.log('FAIL the browser test took over 5 minutes'); cleanup().finally(() => process.exit(1)); }, 300000);

// ---------- the DevTools protocol over --remote-debugging-pipe ----------
class Cdp {
  constructor(proc) {
    this.w = proc.stdio[3]; this.pending = new Map(); this.id = 0; let buf = '';
    proc.stdio[4].on('data', (chunk) => {
      buf += chunk.toString('utf8');
      let at;
      while ((at = buf.indexOf('\0')) >= 0) {
        const msg = JSON.parse(buf.slice(0, at)); buf = buf.slice(at + 1);
        const p = msg.id !== undefined && this.pending.get(msg.id);
        if (p) { this.pending.delete(msg.id); msg.error ? p.reject(new Error(JSON.stringify(msg.error))) : p.resolve(msg.result); }
      }
    });
  }
  send(method, params = {}, sessionId) {
    const id = ++this.id;
    this.w.write(JSON.stringify({ id, method, params, sessionId }) + '\0');
    return new Promise((resolve, reject) => this.pending.set(id, { resolve, reject }));
  }
}

async function openBrowser() {
  const profile = fs.mkdtempSync(path.join(tmp, 'profile-'));
  const proc = spawn(chromium, ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync',
    '--use-angle=swiftshader', '--enable-unsafe-swiftshader', `--user-data-dir=${profile}`,
    '--remote-debugging-pipe', 'about:blank'], { stdio: ['ignore', 'ignore', 'ignore', 'pipe', 'pipe'] });
  children.push(proc);
  const cdp = new Cdp(proc);
  browserCdp = cdp;
  const { targetId } = await cdp.send('Target.createTarget', { url: 'about:blank' });
  const { sessionId } = await cdp.send('Target.attachToTarget', { targetId, flatten: true });
  const page = (m, p) => cdp.send(m, p, sessionId);
  await page('Emulation.setDeviceMetricsOverride', { width: 1280, height: 860, deviceScaleFactor: 1, mobile: false });
  return page;
}

async function evaluate(page, expression) {
  const r = await page('Runtime.evaluate', { expression, awaitPromise: true, returnByValue: true });
  if (r.exceptionDetails) throw new Error(`${expression.slice(0, 80)}…: ${r.exceptionDetails.exception?.description || r.exceptionDetails.text}`);
  return r.result.value;
}
async function until(page, expression, ms = 60000) {
  const end = Date.now() + ms;
  for (;;) {
    const v = await evaluate(page, expression).catch(() => null);
    if (v) return v;
    if (Date.now() > end) throw new Error(`timed out waiting for ${expression}`);
    await new Promise((r) => setTimeout(r, 50));
  }
}

async function startViewer(file) {
  const proc = spawn(bin, ['view', path.basename(file), '--port', '0', '--no-open'], { cwd: path.dirname(file), stdio: ['ignore', 'pipe', 'inherit'] });
  children.push(proc);
  const url = await new Promise((resolve, reject) => {
    let out = '';
    proc.stdout.on('data', (d) => { out += d; const m = out.match(/http:\/\/127\.0\.0\.1:\d+\//); if (m) resolve(m[0]); });
    proc.on('exit', (code) => reject(new Error(`lightpath view exited with ${code}`)));
  });
  return { proc, url };
}

async function load(page, url) {
  await page('Page.navigate', { url });
  try {
    await until(page, `window.lpv && lpv.ready && location.href === ${JSON.stringify(url)} || window.lpv?.error`);
  } catch (e) {
    const state = await evaluate(page, `JSON.stringify({ href: location.href, ready: window.lpv?.ready, timings: window.lpv?.timings, status: document.getElementById('status')?.textContent, drawn: [...document.querySelectorAll('.card canvas')].map((c) => c.width).join(','), perf: performance.getEntriesByType('resource').map((r) => r.name.split('?')[1] + ':' + Math.round(r.duration)).join(' ') })`).catch((x) => x.message);
    throw new Error(`${e.message}; page state ${state}`);
  }
  const error = await evaluate(page, 'lpv.error || null');
  if (error) throw new Error(`the page failed: ${error}`);
}

// Writes a picture of the page (or of `clip`, in page pixels) to DIR/name, reduced to
// 256 dithered colours when Python's PIL is there (a quarter of the size; the docs' are).
async function screenshot(page, name, clip) {
  const { data } = await page('Page.captureScreenshot', { format: 'png', ...(clip ? { clip: { ...clip, scale: 1 } } : {}) });
  const file = path.join(shots, name);
  fs.writeFileSync(file, Buffer.from(data, 'base64'));
  const quantize = 'import sys; from PIL import Image; Image.open(sys.argv[1]).convert("RGB").quantize(256, Image.Quantize.FASTOCTREE).save(sys.argv[1], optimize=True)';
  let how = 'as chromium wrote it (no PIL)';
  try { execFileSync('python3', ['-c', quantize, file], { stdio: 'ignore' }); how = '256 dithered colours'; } catch { /* kept as is */ }
  console.log(`wrote ${file} (${how}, ${fs.statSync(file).size} bytes)`);
}

// Moves sliders and tints through the page's controls, then compares displayed pixels
// with base + (gain − 1)·part computed here from the server's float values.
async function mixerArithmetic(page, label) {
  await evaluate(page, `(() => { const s = document.getElementById('srgb'); s.checked = false; s.dispatchEvent(new Event('change')); })()`);
  const groups = await evaluate(page, `lpv.mixer.groups.map((g) => [g.arg, g.part])`);
  const settings = [[groups[0][0], 2.5, '#ffffff'], [groups[1 % groups.length][0], 0.6, '#ff8000']];
  const before = await evaluate(page, `lpv.idle().then(() => [[8, 8], [32, 24], [50, 40]].map(([x, y]) => lpv.readPixel(x, y)))`);
  for (const [arg, gain, tint] of settings) {
    await evaluate(page, `(() => {
      const row = document.querySelector('.group[data-group="${arg}"]');
      const s = row.querySelector('input[type=range]'); s.value = ${gain}; s.dispatchEvent(new Event('input'));
      const c = row.querySelector('input[type=color]'); c.value = '${tint}'; c.dispatchEvent(new Event('input'));
    })()`);
  }
  await evaluate(page, 'lpv.idle()');
  const gains = new Map(settings.map(([arg, g, t]) => [arg, [1, 3, 5].map((i) => Number((g * parseInt(t.slice(i, i + 2), 16) / 255).toFixed(4)))]));
  const { w, h } = await evaluate(page, `({ w: lpv.info.width, h: lpv.info.height })`);
  let worst = 0, changed = 0, n = 0;
  for (let y = 1; y < h; y += 7) {
    for (let x = 2; x < w; x += 9) {
      const p = await evaluate(page, `fetch('/api/pixel?x=${x}&y=${y}').then((r) => r.json())`);
      const value = (name) => p.values.find((v) => v.name === name).rgb;
      const expected = value(await evaluate(page, 'lpv.mixer.base')).slice();
      for (const [arg, part] of groups) {
        const g = gains.get(arg); if (!g) continue;
        const v = value(part);
        for (let c = 0; c < 3; c++) expected[c] += (g[c] - 1) * v[c];
      }
      const shown = await evaluate(page, `lpv.readPixel(${x}, ${y})`);
      for (let c = 0; c < 3; c++) {
        // Half floats carry 11 significant bits; the display rounds to 1/255.
        const magnitude = Math.abs(value(await evaluate(page, 'lpv.mixer.base'))[c]) + groups.reduce((s, [arg, part]) => s + Math.abs((gains.get(arg)?.[c] ?? 1) - 1) * Math.abs(value(part)[c]), 0);
        const tol = 0.5 + 255 * magnitude * 2 ** -10 + 1e-6;
        const want = 255 * Math.min(Math.max(expected[c], 0), 1);
        worst = Math.max(worst, Math.abs(shown[c] - want) / tol);
      }
      n++;
    }
  }
  const after = await evaluate(page, `[[8, 8], [32, 24], [50, 40]].map(([x, y]) => lpv.readPixel(x, y))`);
  changed = after.filter((a, i) => a.slice(0, 3).some((v, c) => Math.abs(v - before[i][c]) > 2)).length;
  check(worst <= 1, `${label}: ${n} pixels equal base + (gain − 1)·part within half-float and 8-bit rounding (worst ${worst.toFixed(2)} of the tolerance)`);
  check(changed > 0, `${label}: moving the sliders changed the picture`);
  const screen = await onScreen(page);
  check(screen.worst <= 2, `${label}: the screen shows the drawn picture (${screen.n} pixels of a screenshot, worst difference ${screen.worst} of 255)`);
  return settings;
}

// Compares what the browser puts on screen over the large view (a screenshot through
// the DevTools protocol, decoded by the page) with the pixels the renderer drew: an
// element painted over the view, or a view the compositor never shows, fails it.
async function onScreen(page) {
  const [x, y, w, h] = await evaluate(page, `(() => { const r = document.getElementById('view').getBoundingClientRect(); return [r.left + scrollX, r.top + scrollY, r.width, r.height]; })()`);
  const { data } = await page('Page.captureScreenshot', { format: 'png', clip: { x, y, width: w, height: h, scale: 1 } });
  return evaluate(page, `(async () => {
    const view = document.getElementById('view');
    const shot = await createImageBitmap(await (await fetch('data:image/png;base64,${data}')).blob());
    const c = document.createElement('canvas'); c.width = shot.width; c.height = shot.height;
    const ctx = c.getContext('2d'); ctx.drawImage(shot, 0, 0);
    const px = ctx.getImageData(0, 0, c.width, c.height).data;
    let worst = shot.width === view.width && shot.height === view.height ? 0 : 255, n = 0;
    for (let y = 1; y < Math.min(c.height, view.height); y += 4) {
      for (let x = 1; x < Math.min(c.width, view.width); x += 4) {
        const drawn = lpv.readPixel(x, y), i = 4 * (y * c.width + x);
        for (let k = 0; k < 3; k++) worst = Math.max(worst, Math.abs(px[i + k] - drawn[k]));
        n++;
      }
    }
    return { worst, n };
  })()`);
}

async function main() {
  if (perf) return measure(perf);
  if (shots) return pictures(shots);
  const shot = path.join(tmp, 'shot.exr');
  execFileSync(bin, ['render', 'cornell', '--resolution', '64x48', '--spp', '4', '--light-groups', '--bounces', '1', '--quiet', '-o', shot]);
  const listing = execFileSync(bin, ['aovs', shot]).toString().split('\n');
  const expected = listing.filter((l) => /^ {2}\S/.test(l)).map((l) => { const m = l.match(/^ {2}(\S+)\s+(.*)$/); return [m[1], m[2]]; });
  const partitions = listing.filter((l) => /^(ok |FAIL)/.test(l)).length;
  const { url } = await startViewer(shot);
  const page = await openBrowser();
  await load(page, url);
  const renderer = await evaluate(page, 'lpv.renderer.name');
  check(renderer === 'WebGL2', `the large view is drawn with WebGL2 (${renderer}${await evaluate(page, 'lpv.gpuError || ""')})`);
  const shown = await evaluate(page, `[...document.querySelectorAll('.card[data-aov]')].map((e) => [e.dataset.aov, e.querySelector('.expr').textContent])`);
  const key = (l) => l.map(([n, d]) => `${n}\t${d}`).sort().join('\n');
  check(shown.length === expected.length && key(shown) === key(expected), `the list shows all ${expected.length} AOVs of the file, each with its expression`);
  // The checks are measured on the server's own thread; the page polls for them.
  const checks = await until(page, `document.querySelectorAll('.partition .check.ok').length === ${partitions} && ${partitions}`, 20000).catch(() => 0);
  check(checks === partitions && partitions > 0, `every partition (${partitions}) is shown with its measured error, within tolerance`);
  const drawnThumbs = await evaluate(page, `[...document.querySelectorAll('.card canvas')].filter((c) => c.width > 0).length`);
  check(drawnThumbs === expected.length, 'every thumbnail is drawn');

  // The pixel inspector: move the mouse over the image.
  const box = await evaluate(page, `(() => { const r = document.getElementById('view').getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; })()`);
  await page('Input.dispatchMouseEvent', { type: 'mouseMoved', x: box[0] + box[2] / 2, y: box[1] + box[3] / 2 });
  const rows = await until(page, `document.querySelectorAll('#pixel tbody tr').length`);
  check(rows === expected.length, `the pixel inspector lists the values of all ${expected.length} AOVs`);

  const settings = await mixerArithmetic(page, 'WebGL2');

  // Save comp, then run the command line the page shows.
  await evaluate(page, `(() => { document.getElementById('comp-name').value = 'relit_page.exr'; document.getElementById('save-comp').click(); })()`);
  const saved = await until(page, 'lpv.saved');
  check(!saved.error, `Save comp wrote the comp (${saved.error || saved.command})`);
  if (!saved.error) {
    const words = saved.command.split(' ');
    const gainArgs = words.filter((w, i) => words[i - 1] === '--gain');
    check(settings.every(([arg]) => gainArgs.some((g) => g.startsWith(`${arg}=`))), `the command line carries every moved slider: ${gainArgs.join(' ')}`);
    words[words.indexOf('-o') + 1] = 'relit_cli.exr';
    execFileSync(bin, words.slice(1), { cwd: tmp });
    const a = fs.readFileSync(path.join(tmp, 'relit_page.exr')), b = fs.readFileSync(path.join(tmp, 'relit_cli.exr'));
    check(a.equals(b), 'the saved comp is byte for byte the file its `lightpath comp` command line writes');
  }

  // The CPU fallback draws the same arithmetic.
  await load(page, `${url}?cpu=1`);
  check((await evaluate(page, 'lpv.renderer.name')) === 'CPU', 'the CPU fallback is drawn with ?cpu');
  await mixerArithmetic(page, 'CPU');
}

// Times the page on a file: info, the beauty at full size, every thumbnail, then a click
// on each of a few AOVs until it is drawn at full size.
async function measure(file) {
  const { url } = await startViewer(file);
  const page = await openBrowser();
  const t0 = Date.now();
  await load(page, url);
  const wall = Date.now() - t0;
  const t = await evaluate(page, 'lpv.timings');
  const n = await evaluate(page, `document.querySelectorAll('.card').length`);
  console.log(`page, from the navigation: script ${t.script.toFixed(0)} ms, info ${t.info.toFixed(0)} ms, beauty ${t.beauty.toFixed(0)} ms (fetch ${t.view.fetch.toFixed(0)}, draw ${t.view.draw.toFixed(0)}), all ${n} thumbnails ${t.thumbnails.toFixed(0)} ms (${wall} ms seen from here)`);
  const names = await evaluate(page, `[...document.querySelectorAll('.card[data-aov]')].map((e) => e.dataset.aov).slice(1, 6)`);
  for (const name of names) {
    // Reading a pixel back waits for the GPU to finish the draw.
    const [ms, v] = await evaluate(page, `(async () => { const t = performance.now(); document.querySelector('.card[data-aov="${name}"]').click(); await lpv.idle(); lpv.readPixel(0, 0); return [performance.now() - t, lpv.timings.view]; })()`);
    console.log(`click ${name}: drawn at full size in ${ms.toFixed(0)} ms (fetch ${v.fetch.toFixed(0)}, upload and draw ${(ms - v.fetch - v.parts).toFixed(0)})`);
  }
}

// The pictures of docs/aovs.md: the page as it opens, the mixer after moving two groups
// (and saving the comp), the pixel inspector with a Cryptomatte pick.
async function pictures(dir) {
  fs.mkdirSync(dir, { recursive: true });
  let file = opt('--exr') && path.resolve(opt('--exr'));
  if (!file) {
    file = path.join(tmp, 'cornell.exr');
    const spp = opt('--spp') || '64';
    execFileSync(bin, ['render', 'cornell', '--resolution', '640x480', '--spp', spp, '--light-groups', '--cryptomatte', '--quiet', '-o', file], { stdio: 'inherit' });
  }
  const { url } = await startViewer(file);
  const page = await openBrowser();
  await page('Emulation.setDeviceMetricsOverride', { width: 1024, height: 880, deviceScaleFactor: 1, mobile: false });
  await load(page, url);
  await until(page, `document.querySelectorAll('.partition .check.ok, .partition .check.bad').length === lpv.info.partitions.length`, 60000);
  await evaluate(page, 'lpv.idle()');
  await screenshot(page, 'view-overview.png');

  if (!(await evaluate(page, '!!lpv.mixer'))) throw new Error(`${file} has no light groups: the mixer's picture needs a render with --light-groups`);
  const groups = await evaluate(page, `lpv.mixer.groups.map((g) => g.arg)`);
  const pickGroup = (name, i) => (groups.includes(name) ? name : groups[i]);
  for (const [arg, gain, tint] of [[pickGroup('key', 0), 0.3, '#ffffff'], [pickGroup('fill', 1), 3, '#ffb060']]) {
    await evaluate(page, `(() => {
      const row = document.querySelector('.group[data-group="${arg}"]');
      const s = row.querySelector('input[type=range]'); s.value = ${gain}; s.dispatchEvent(new Event('input'));
      const c = row.querySelector('input[type=color]'); c.value = '${tint}'; c.dispatchEvent(new Event('input'));
    })()`);
  }
  await evaluate(page, 'lpv.idle()');
  await evaluate(page, `document.getElementById('save-comp').click()`);
  await until(page, 'lpv.saved');
  // The viewer column scrolled to the mixer.
  await evaluate(page, `document.getElementById('mixer').scrollIntoView({ block: 'end' })`);
  await screenshot(page, 'view-mixer.png');

  // The inspector: the cursor over the glossy ball, which is picked (its matte, its name).
  await evaluate(page, `document.getElementById('reset').click()`);
  await evaluate(page, 'lpv.idle()');
  await evaluate(page, `document.getElementById('viewer').scrollTop = 0`);
  const box = await evaluate(page, `(() => { const r = document.getElementById('view').getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; })()`);
  const at = { x: box[0] + 0.5 * box[2], y: box[1] + 0.79 * box[3] };
  await page('Input.dispatchMouseEvent', { type: 'mouseMoved', ...at });
  await page('Input.dispatchMouseEvent', { type: 'mousePressed', ...at, button: 'left', clickCount: 1 });
  await page('Input.dispatchMouseEvent', { type: 'mouseReleased', ...at, button: 'left', clickCount: 1 });
  await until(page, `document.querySelectorAll('#pixel tbody tr').length && (!lpv.info.cryptomatte.length || lpv.picked)`);
  // Tall enough for the whole table; the picture is the viewer column down to the table.
  await page('Emulation.setDeviceMetricsOverride', { width: 1024, height: 1500, deviceScaleFactor: 1, mobile: false });
  await new Promise((r) => setTimeout(r, 300));
  await evaluate(page, 'drawView().then(() => lpv.idle())');
  const v = await evaluate(page, `(() => { const r = document.getElementById('viewer').getBoundingClientRect(), t = document.getElementById('inspector').getBoundingClientRect(); return [r.left, r.top, r.width, Math.min(r.bottom, t.bottom + 10) - r.top]; })()`);
  await screenshot(page, 'view-inspector.png', { x: v[0], y: v[1], width: v[2], height: v[3] });
}

main()
  .catch((e) => { check(false, e.stack || e.message); })
  .finally(async () => {
    clearTimeout(timeout);
    await cleanup();
    if (!perf && !shots) console.log(`${passed} passed, ${failed} failed`);
    process.exit(failed ? 1 : 0);
  });
