#!/usr/bin/env node
// Renders GLB files in headless Chromium with three.js (GLTFLoader + DRACOLoader, WebGL on SwiftShader,
// so no GPU is needed) and measures from the pixels whether the surface is shaded smoothly or in facets.
//
//   node render_glb.js [options] FILE.glb ...      render each file; fail (1) if any is faceted
//   node render_glb.js [options] --calibrate DIR   write one icosphere with and without NORMAL as GLB,
//                                                 render both; fail (1) unless the metric separates them
//   node render_glb.js [options] --normalflow BIN DIR   write the same icosphere as .obj, have normalflow
//                                                 smooth it to a Draco GLB (smooth), and write it with its
//                                                 normals as Draco GLB (compress) and plain GLB (convert);
//                                                 render the three; fail (1) if any is faceted
// Options: --modules DIR   node_modules with three and playwright-core (default: $NORMALFLOW_NODE_MODULES,
//                          else node_modules beside this script; scripts/test installs <build>/tools/node_modules)
//          --chromium EXE  (default: chromium, chromium-browser or google-chrome on PATH)
//          --size N        frame size in pixels (512)
// Prints one JSON line. Next to each GLB it leaves FILE.png, the rendered frame, for people to look at.
// Exit: 0 smooth (or calibration separates), 1 faceted (or calibration does not separate), 2 a page
// failed to load or render, 77 skipped: no chromium or no node_modules (ctest SKIP_RETURN_CODE).
//
// The figure, `step_fraction`: a flat-shaded mesh is a mosaic of constant-luminance facets, so its
// picture has luminance steps along the facet edges; smooth shading (per-pixel lighting of interpolated
// vertex normals) is continuous, with at most a gently varying gradient. We take the luminance
// Y = 0.2126 R + 0.7152 G + 0.0722 B (0..255) of the pixels inside the silhouette, eroded by 2 pixels so
// that the outline and its neighbours do not count, and at every pixel the second difference along
// x and along y, |Y(p-1) - 2 Y(p) + Y(p+1)|: it is ~0 on a smooth ramp however steep, and equal to the
// step height on both sides of a discontinuity. step_fraction is the fraction of (pixel, axis) samples
// whose second difference exceeds STEP_LEVEL grey levels. The level and the pass/fail line are set by
// the calibration (--calibrate, see README.md): the same sphere is rendered with and without NORMAL.
'use strict';
const fs = require('fs');
const http = require('http');
const path = require('path');
const { execFileSync } = require('child_process');
const sphere = require('./sphere_glb.js');

const STEP_LEVEL = 2;          // grey levels: a second difference above it is a step (see README.md)
const FACETED_ABOVE = 0.002;   // step_fraction above this is faceted (see README.md)
const MARGIN = 4;              // calibration: each sphere at least this factor away from FACETED_ABOVE
const SPHERE_LEVEL = 3;        // the sphere given to normalflow: 1280 triangles, 642 vertices
const CALIBRATION_LEVELS = [3, 5];   // 1280 and 20480 triangles
const SKIP = 77;

function parseArgs(argv) {
  const o = { modules: process.env.NORMALFLOW_NODE_MODULES || path.join(__dirname, 'node_modules'),
              chromium: null, size: 512, files: [], calibrate: null, normalflow: null };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '--modules') o.modules = argv[++i];
    else if (a === '--chromium') o.chromium = argv[++i];
    else if (a === '--size') o.size = Number(argv[++i]);
    else if (a === '--calibrate') o.calibrate = argv[++i];
    else if (a === '--normalflow') { o.normalflow = argv[++i]; o.workdir = argv[++i]; }
    else if (a.startsWith('--')) throw new Error('unknown option ' + a);
    else o.files.push(a);
  }
  o.modules = path.resolve(o.modules);
  return o;
}

function findChromium() {
  for (const name of ['chromium', 'chromium-browser', 'google-chrome']) {
    for (const dir of (process.env.PATH || '').split(':')) {
      const p = path.join(dir, name);
      try { fs.accessSync(p, fs.constants.X_OK); return p; } catch (e) { /* next */ }
    }
  }
  return null;
}

// A static server on 127.0.0.1, random port: /page/* from page/, /modules/* from node_modules,
// /glb/<i> the i-th GLB. Nothing else is readable.
function serve(modules, glbs) {
  const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript',
                  '.wasm': 'application/wasm', '.json': 'application/json' };
  const pageDir = path.join(__dirname, 'page');
  const server = http.createServer((req, res) => {
    const url = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    let file = null;
    if (url === '/favicon.ico') { res.writeHead(204); res.end(); return; }
    if (url.startsWith('/glb/')) file = glbs[Number(url.slice(5))];
    else if (url.startsWith('/page/')) file = path.join(pageDir, path.normalize(url.slice(6)));
    else if (url.startsWith('/modules/')) file = path.join(modules, path.normalize(url.slice(9)));
    const inside = file && (url.startsWith('/glb/') || file.startsWith(pageDir) || file.startsWith(path.resolve(modules)));
    if (!inside || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      res.writeHead(404); res.end(); return;
    }
    res.writeHead(200, { 'Content-Type': types[path.extname(file)] || 'application/octet-stream' });
    fs.createReadStream(file).pipe(res);
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server)));
}

function measure(shaded, mask, size) {
  const Y = new Float32Array(size * size), inside = new Uint8Array(size * size);
  for (let i = 0; i < size * size; i++) {
    Y[i] = 0.2126 * shaded[4 * i] + 0.7152 * shaded[4 * i + 1] + 0.0722 * shaded[4 * i + 2];
    inside[i] = mask[4 * i] > 127 ? 1 : 0;
  }
  const R = 2;  // erosion radius: a sample counts when its whole (2R+1)^2 neighbourhood is inside
  const core = new Uint8Array(size * size);
  let silhouette = 0;
  for (let y = 0; y < size; y++)
    for (let x = 0; x < size; x++) {
      silhouette += inside[y * size + x];
      if (x < R || y < R || x >= size - R || y >= size - R) continue;
      let all = 1;
      for (let dy = -R; dy <= R && all; dy++)
        for (let dx = -R; dx <= R; dx++) if (!inside[(y + dy) * size + x + dx]) { all = 0; break; }
      core[y * size + x] = all;
    }
  let samples = 0, steps = 0, sumY = 0, n = 0;
  for (let y = 1; y < size - 1; y++)
    for (let x = 1; x < size - 1; x++) {
      const i = y * size + x;
      if (!core[i]) continue;
      n++; sumY += Y[i];
      for (const d of [1, size]) {
        const s = Math.abs(Y[i - d] - 2 * Y[i] + Y[i + d]);
        samples++;
        if (s > STEP_LEVEL) steps++;
      }
    }
  return { silhouette_pixels: silhouette, interior_pixels: n, mean_luminance: n ? sumY / n : 0,
           step_fraction: samples ? steps / samples : 0 };
}

async function renderAll(opt, glbs) {
  const pw = require(path.join(opt.modules, 'playwright-core'));
  const server = await serve(opt.modules, glbs);
  const port = server.address().port;
  const browser = await pw.chromium.launch({
    executablePath: opt.chromium, headless: true,
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--no-sandbox'],
  });
  const out = [];
  try {
    for (let i = 0; i < glbs.length; i++) {
      const page = await browser.newPage({ viewport: { width: opt.size, height: opt.size } });
      const log = [];
      page.on('console', (m) => log.push(m.text()));
      page.on('pageerror', (e) => log.push(String(e)));
      const r = { file: glbs[i] };
      try {
        await page.goto(`http://127.0.0.1:${port}/page/index.html?glb=/glb/${i}&size=${opt.size}`);
        await page.waitForFunction(() => document.title === 'done', null, { timeout: 60000 });
        const res = await page.evaluate(() => window.result);
        if (!res || !res.ok) throw new Error((res && res.error) || 'no result');
        r.ok = true;
        r.gl_renderer = res.glRenderer;
        r.normal_in_file = res.filePrimitives.every((p) => p.attributes.includes('NORMAL') ||
                                                    (p.draco || []).includes('NORMAL'));
        r.file_primitives = res.filePrimitives;
        r.loaded = res.loaded;
        Object.assign(r, measure(Buffer.from(res.shaded, 'base64'), Buffer.from(res.mask, 'base64'), res.size));
        r.screenshot = glbs[i].replace(/\.glb$/i, '') + '.png';
        await page.locator('canvas').screenshot({ path: r.screenshot });
        if (r.interior_pixels < 1000) throw new Error(`only ${r.interior_pixels} pixels inside the silhouette`);
        r.verdict = r.step_fraction > FACETED_ABOVE ? 'faceted' : 'smooth';
      } catch (e) {
        r.ok = false;
        r.error = String(e.message || e).split('\n')[0];
        if (log.length) r.console = log.slice(-5);
      }
      out.push(r);
      await page.close();
    }
  } finally {
    await browser.close();
    server.close();
  }
  return out;
}

async function main() {
  const opt = parseArgs(process.argv.slice(2));
  const result = { step_level: STEP_LEVEL, faceted_above: FACETED_ABOVE };
  if (!fs.existsSync(path.join(opt.modules, 'playwright-core')) || !fs.existsSync(path.join(opt.modules, 'three'))) {
    console.log(JSON.stringify({ skipped: `no three/playwright-core in ${opt.modules} (npm ci in tests/browser, or scripts/test)` }));
    return SKIP;
  }
  opt.chromium = opt.chromium || findChromium();
  if (!opt.chromium) {
    console.log(JSON.stringify({ skipped: 'no chromium on PATH (scripts/setup installs it)' }));
    return SKIP;
  }
  let glbs = opt.files;
  if (opt.calibrate) {
    fs.mkdirSync(opt.calibrate, { recursive: true });
    glbs = [];
    for (const level of CALIBRATION_LEVELS) {
      const m = sphere.icosphere(level);
      for (const normals of [true, false]) {
        glbs.push(path.join(opt.calibrate, `sphere${level}_${normals ? 'normals' : 'no_normals'}.glb`));
        sphere.writeGlb(glbs[glbs.length - 1], m, { normals });
      }
    }
    result.mode = 'calibrate';
  } else if (opt.normalflow) {
    fs.mkdirSync(opt.workdir, { recursive: true });
    // The sphere without normals through `smooth` (its GLB's normals come from the processed volume),
    // and with normals (OBJ vn) through `compress` (Draco GLB) and `convert` (plain GLB).
    const bare = path.join(opt.workdir, 'sphere.obj'), withNormals = path.join(opt.workdir, 'sphere_vn.obj');
    sphere.writeObj(bare, sphere.icosphere(SPHERE_LEVEL));
    sphere.writeObj(withNormals, sphere.icosphere(SPHERE_LEVEL), { normals: true });
    glbs = ['sphere_smooth.glb', 'sphere_compress.glb', 'sphere_convert.glb'].map((f) => path.join(opt.workdir, f));
    const run = (args) => execFileSync(opt.normalflow, args, { stdio: ['ignore', 'ignore', 'inherit'] });
    run(['smooth', bare, glbs[0], '--resolution', '64', '--quiet']);
    run(['compress', withNormals, glbs[1], '--quiet']);
    run(['convert', withNormals, glbs[2]]);
    result.mode = 'normalflow';
  }
  if (!glbs.length) throw new Error('no GLB given (see the usage at the top of render_glb.js)');
  result.results = await renderAll(opt, glbs.map((f) => path.resolve(f)));
  const ok = result.results.every((r) => r.ok);
  if (opt.calibrate) {
    // Pairs (with NORMAL, without): the first must be MARGIN times below the line, the second above.
    result.margin = MARGIN;
    result.pass = ok;
    for (let i = 0; ok && i < glbs.length; i += 2) {
      const smooth = result.results[i].step_fraction, flat = result.results[i + 1].step_fraction;
      result.pass = result.pass && smooth * MARGIN <= FACETED_ABOVE && flat >= FACETED_ABOVE * MARGIN;
    }
  } else {
    result.pass = ok && result.results.every((r) => r.verdict === 'smooth');
  }
  console.log(JSON.stringify(result));
  return ok ? (result.pass ? 0 : 1) : 2;
}

main().then((code) => process.exit(code), (e) => {
  console.log(JSON.stringify({ ok: false, error: String(e.message || e).split('\n')[0] }));
  process.exit(2);
});
