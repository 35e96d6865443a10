// The page `corrlap view` writes, in headless Chromium (WebGL on SwiftShader, no GPU needed), through
// its API (viewer/README.md, "What the page offers"): it loads from file:// without any other
// request, draws the meshes where the camera looks, and setField, setVisible, setLayout, setShading,
// setWireframe and pick do what they say, judged on screenshots of the canvas; the page regularize
// writes loads too.
// Usage: node browser_test.mjs CORRLAP SCRATCH_DIR NODE_MODULES_DIR   (ctest viewer_browser)
// NODE_MODULES_DIR holds playwright-core (viewer/package.json; the build runs `npm ci` into
// <build>/viewer). The browser: $CHROMIUM, else /usr/bin/chromium (scripts/install_deps.sh --chromium).
// Exit 0 passed, 77 skipped (no Chromium or no playwright-core), 1 failed.
import { execFileSync } from "node:child_process";
import { accessSync, constants, existsSync, mkdirSync, statSync } from "node:fs";
import { createRequire } from "node:module";
import { join, resolve } from "node:path";
import { pathToFileURL } from "node:url";

const started = Date.now();
const [cli, scratchArg, nodeModulesArg] = process.argv.slice(2);
if (!cli || !scratchArg || !nodeModulesArg) {
  console.error("usage: node browser_test.mjs CORRLAP SCRATCH_DIR NODE_MODULES_DIR");
  process.exit(2);
}
const scratch = resolve(scratchArg);
const nodeModules = resolve(nodeModulesArg);

function skip(why) {
  console.log(`skipped: ${why}`);
  process.exit(77);
}
class Failure extends Error {}
function check(ok, message) {
  if (!ok) throw new Failure(message);
}
const log = (message) => console.log(`[${((Date.now() - started) / 1000).toFixed(1)} s] ${message}`);

// --- What the test needs; without it, skip. ---
// playwright-core 1.65 needs Node 20 (Debian 12's own nodejs is 18; the build's bundling works with it).
if (Number(process.versions.node.split(".")[0]) < 20)
  skip(`playwright-core needs Node 20 or later, this is Node ${process.versions.node}`);
let playwright;
try {
  playwright = createRequire(join(nodeModules, "package.json"))("playwright-core");
} catch {
  skip(`playwright-core not found in ${nodeModules} (the build installs it there with npm ci when node and npm are found)`);
}
const chromiumPath = process.env.CHROMIUM || "/usr/bin/chromium";
try {
  accessSync(chromiumPath, constants.X_OK);
} catch {
  skip(`no Chromium at ${chromiumPath} (set CHROMIUM, or scripts/install_deps.sh --chromium)`);
}

// Headless is Chromium's own (new) headless mode, the only one since Chromium 132. WebGL runs on
// SwiftShader through ANGLE: no GPU or display needed. playwright-core adds --headless,
// --no-sandbox and --disable-dev-shm-usage itself; these are the flags a person would pass by hand.
const flags = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"];
const W = 800, H = 600;
const problems = [];  // page errors, console errors and crashes: failed at the end (or with the first failure)
const requests = [];  // every request of the pages under test: only their own file:// URLs may be there
let browser;
let status = 1;
function run(args) {
  try {
    return execFileSync(cli, args, { encoding: "utf8", stdio: ["ignore", "pipe", "pipe"] });
  } catch (e) {
    const why = e.status !== null && e.status !== undefined ? `exit ${e.status}` : e.message;
    throw new Failure(`corrlap ${args.join(" ")} failed (${why}):\n${e.stdout || ""}${e.stderr || ""}`);
  }
}
try {
  // Inputs: two spheres from the CLI, the staircase and its regularization (each with H; the second
  // with the displacement too). regularize writes a page of them too (view.html, side by side).
  mkdirSync(scratch, { recursive: true });
  const meshDir = join(scratch, "sphere");
  run(["regularize", "--shape", "sphere1", "--h", "0.1", "--no-render", "--out", meshDir]);
  const inputs = [join(meshDir, "input.ply"), join(meshDir, "regularized.ply")];
  for (const f of inputs) check(existsSync(f), `corrlap regularize did not write ${f}`);
  const pagePath = join(scratch, "view.html");
  run(["view", ...inputs, "--scalar", "H", "--layout", "overlay", "--out", pagePath]);
  check(existsSync(pagePath), `corrlap view did not write ${pagePath}`);
  log(`inputs and page written (${(statSync(pagePath).size / 1024).toFixed(0)} KiB)`);

  // The browser.
  try {
    browser = await playwright.chromium.launch({ executablePath: chromiumPath, headless: true, args: flags, timeout: 30000 });
  } catch (e) {
    throw new Failure(`cannot start ${chromiumPath} with ${flags.join(" ")}: ${e.message}`);
  }
  const context = await browser.newContext({ viewport: { width: W, height: H }, deviceScaleFactor: 1 });
  // Recorded below and failed at the end; aborted meanwhile, so that the test never reaches out.
  await context.route(/^(https?|wss?|ftp):/, (route) => route.abort());
  const readyTimeout = 30000;
  // A page under test, open and ready (its requests, errors and console errors recorded); the time
  // from navigation start to corrlapView.ready.
  async function openPage(path) {
    const page = await context.newPage();
    const url = pathToFileURL(path).href;
    page.on("request", (r) => requests.push({ page: url, url: r.url() }));
    page.on("pageerror", (e) => problems.push(`${path}: page error: ${e.message}`));
    page.on("console", (m) => {
      if (m.type() === "error") problems.push(`${path}: console error: ${m.text()}`);
    });
    page.on("crash", () => problems.push(`${path}: the page crashed`));
    await page.goto(url, { waitUntil: "commit", timeout: readyTimeout });
    const outcome = await page.evaluate(
      (ms) =>
        new Promise((done) => {
          const state = () => `body data-ready=${document.body?.dataset.ready ?? "(none)"} data-error=${document.body?.dataset.error ?? "(none)"}`;
          const timer = setTimeout(() => done(`timeout: corrlapView.ready did not settle within ${ms / 1000} s (${state()})`), ms);
          const start = () => {
            if (!window.corrlapView || !window.corrlapView.ready) return false;
            window.corrlapView.ready.then(
              () => (clearTimeout(timer), done(`ready ${performance.now()}`)),
              (e) => (clearTimeout(timer), done(`rejected: ${e && e.message ? e.message : e} (${state()})`)));
            return true;
          };
          if (!start()) {  // the API object appears when the page's script runs
            const poll = setInterval(() => start() && clearInterval(poll), 10);
            setTimeout(() => clearInterval(poll), ms);
          }
        }),
      readyTimeout);
    check(outcome.startsWith("ready "), `${path} did not become ready: ${outcome}${problems.length ? "\n  " + problems.join("\n  ") : ""}`);
    const body = await page.evaluate(() => ({ ready: document.body.dataset.ready, error: document.body.dataset.error }));
    check(body.ready === "1", `${path}: corrlapView.ready resolved but body data-ready is ${body.ready}`);
    check(body.error === undefined, `${path}: corrlapView.ready resolved but body data-error is "${body.error}"`);
    return { page, url, loadMs: Number(outcome.slice(6)) };
  }

  const { page, loadMs } = await openPage(pagePath);
  log(`ready in ${loadMs.toFixed(0)} ms (navigation start to corrlapView.ready)`);

  const api = await page.evaluate(() => ({ fields: window.corrlapView.fields, meshes: window.corrlapView.meshes }));
  check(Array.isArray(api.fields) && api.fields.includes("H") && api.fields.includes("displacement"),
    `corrlapView.fields: expected H and displacement, got ${JSON.stringify(api.fields)}`);
  check(Array.isArray(api.meshes) && api.meshes.length === 2, `corrlapView.meshes: expected 2 names, got ${JSON.stringify(api.meshes)}`);

  // The WebGL canvas: the largest one. Every other element is hidden in the screenshots (titles,
  // menus, colour bars), so that the pixels are the canvas'.
  const canvasBox = await page.evaluate(() => {
    const canvases = [...document.querySelectorAll("canvas")];
    if (!canvases.length) return null;
    const c = canvases.reduce((a, b) => (b.clientWidth * b.clientHeight > a.clientWidth * a.clientHeight ? b : a));
    c.setAttribute("data-browser-test-canvas", "");
    const r = c.getBoundingClientRect();
    return { x: r.left, y: r.top, width: r.width, height: r.height };
  });
  check(canvasBox && canvasBox.width >= 200 && canvasBox.height >= 200,
    `expected a canvas of at least 200 x 200 CSS pixels in a ${W} x ${H} window, got ${JSON.stringify(canvasBox)}`);
  await page.screenshot({ path: join(scratch, "page.png") });  // the whole page, for a person to look at
  await page.addStyleTag({
    content: "body *:not([data-browser-test-canvas]):not(:has([data-browser-test-canvas])) { visibility: hidden !important; }",
  });
  const centre = [canvasBox.width / 2, canvasBox.height / 2];

  // Pixels are read in a second, blank page: the screenshot as an image drawn into a 2D canvas.
  const lab = await context.newPage();
  await lab.setContent("<canvas></canvas>");
  async function shot(name) {
    const png = await page.screenshot({ clip: canvasBox, path: join(scratch, `${name}.png`) });
    return png.toString("base64");
  }
  // Statistics of picture `a` against background picture `bg` (same size): coverage (fraction of
  // pixels that differ from the background), bounding box of those pixels, the centre pixel; and,
  // with `b`, the fraction of the pixels covered in a or b that differ between a and b.
  async function measure(a, bg, b = null) {
    return lab.evaluate(
      async ([a, bg, b]) => {
        const load = async (s) => {
          const img = new Image();
          img.src = "data:image/png;base64," + s;
          await img.decode();
          const c = document.querySelector("canvas");
          c.width = img.width;
          c.height = img.height;
          const g = c.getContext("2d", { willReadFrequently: true });
          g.drawImage(img, 0, 0);
          return g.getImageData(0, 0, img.width, img.height);
        };
        const A = await load(a), G = await load(bg), B = b ? await load(b) : null;
        const w = A.width, h = A.height;
        const differ = (P, Q, i) =>
          Math.max(Math.abs(P.data[i] - Q.data[i]), Math.abs(P.data[i + 1] - Q.data[i + 1]), Math.abs(P.data[i + 2] - Q.data[i + 2])) > 24;
        let covered = 0, union = 0, changed = 0, x0 = w, x1 = -1, y0 = h, y1 = -1;
        for (let y = 0; y < h; y++)
          for (let x = 0; x < w; x++) {
            const i = 4 * (y * w + x);
            const inA = differ(A, G, i);
            if (inA) {
              covered++;
              x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y);
            }
            if (B && (inA || differ(B, G, i))) {
              union++;
              if (differ(A, B, i)) changed++;
            }
          }
        const ci = 4 * (Math.floor(h / 2) * w + Math.floor(w / 2));
        return {
          w, h, coverage: covered / (w * h), bbox: covered ? { x0, x1, y0, y1 } : null,
          centre: [A.data[ci], A.data[ci + 1], A.data[ci + 2]], centreCovered: differ(A, G, ci),
          changed: B ? (union ? changed / union : 0) : null,
        };
      },
      [a, bg, b]);
  }
  // An API call, awaited in the page: a Promise that does not settle within 15 s fails the test.
  async function call(method, ...args) {
    const r = await page.evaluate(
      ([m, a]) =>
        Promise.race([
          Promise.resolve(window.corrlapView[m](...a)).then(() => "ok", (e) => `rejected: ${e && e.message ? e.message : e}`),
          new Promise((done) => setTimeout(() => done("did not settle within 15 s"), 15000)),
        ]),
      [method, args]);
    check(r === "ok", `corrlapView.${method}(${args.map((a) => JSON.stringify(a)).join(", ")}): ${r}`);
  }
  const pick = (x, y) => page.evaluate(([x, y]) => window.corrlapView.pick(x, y), [x, y]);
  const pct = (f) => `${(100 * f).toFixed(1)} %`;
  // pick's `mesh`: the mesh's index, or its name (README: "{mesh, ...}"); -1 when neither.
  const meshIndex = (hit) =>
    Number.isInteger(hit.mesh) ? (hit.mesh >= 0 && hit.mesh < api.meshes.length ? hit.mesh : -1) : api.meshes.indexOf(hit.mesh);

  // 1. The first frame, and the background alone (every mesh hidden).
  const first = await shot("initial");
  for (let i = 0; i < api.meshes.length; i++) await call("setVisible", i, false);
  const bg = await shot("hidden");
  check((await pick(...centre)) === null, "pick at the canvas centre hits a face while every mesh is hidden");
  const empty = await measure(bg, bg, first);
  check(empty.changed > 0.9, `hiding every mesh left the picture almost as it was (${pct(empty.changed)} of the pixels changed)`);
  for (let i = 0; i < api.meshes.length; i++) await call("setVisible", i, true);
  const shown = await measure(await shot("shown-again"), bg, first);
  check(shown.changed < 0.02, `showing the meshes again did not give the first frame back (${pct(shown.changed)} of the pixels differ)`);

  const m0 = await measure(first, bg);
  log(`initial frame: ${pct(m0.coverage)} of the canvas covered, bbox ${JSON.stringify(m0.bbox)}, centre pixel ${m0.centre}`);
  check(m0.coverage > 0.05 && m0.coverage < 0.8, `the meshes cover ${pct(m0.coverage)} of the canvas: expected 5-80 % (the camera does not frame them)`);
  check(m0.centreCovered, "the canvas centre shows the background: the meshes are not where the camera looks");
  // Framed whole (the page may shift them aside, e.g. beside its panel): not cut by the canvas' edges.
  check(m0.bbox.x0 > 0 && m0.bbox.y0 > 0 && m0.bbox.x1 < m0.w - 1 && m0.bbox.y1 < m0.h - 1,
    `the meshes are cut by the canvas' edges: covered pixels span ${JSON.stringify(m0.bbox)} of ${m0.w} x ${m0.h}`);

  // 2. Overlaid, hiding the staircase leaves the regularized sphere where it was (the view does not
  // move), inside the staircase: a little less covered; pick finds it.
  await call("setVisible", 0, false);
  const inner = await measure(await shot("overlay-staircase-hidden"), bg, first);
  log(`overlaid, staircase hidden: coverage ${pct(inner.coverage)} (both: ${pct(m0.coverage)}), ${pct(inner.changed)} of the covered pixels changed`);
  check(inner.coverage <= m0.coverage && inner.coverage > 0.7 * m0.coverage,
    `overlaid, hiding the staircase (mesh 0): coverage ${pct(m0.coverage)} -> ${pct(inner.coverage)}, expected a little less`);
  check(inner.changed > 0.1, `overlaid, hiding the staircase changed only ${pct(inner.changed)} of the covered pixels`);
  const innerHit = await pick(...centre);
  check(innerHit && meshIndex(innerHit) === 1, `overlaid, staircase hidden: pick at the centre gave ${JSON.stringify(innerHit)}, expected mesh 1`);
  await call("setVisible", 0, true);

  // 3. pick at the centre: a face of one of the meshes with a finite H.
  const hit = await pick(...centre);
  check(hit !== null && typeof hit === "object", `pick at the canvas centre (${centre}) returned ${JSON.stringify(hit)}: expected a hit`);
  check(meshIndex(hit) >= 0, `pick: bad mesh ${JSON.stringify(hit)} (meshes ${JSON.stringify(api.meshes)})`);
  check(Number.isInteger(hit.face) && hit.face >= 0, `pick: bad face ${JSON.stringify(hit)}`);
  check(Number.isInteger(hit.vertex) && hit.vertex >= 0, `pick: bad vertex ${JSON.stringify(hit)}`);
  check(Array.isArray(hit.position) && hit.position.length === 3 && hit.position.every(Number.isFinite), `pick: bad position ${JSON.stringify(hit)}`);
  check(Number.isFinite(hit.value), `pick at the centre with field H: expected a finite value, got ${JSON.stringify(hit)}`);
  // The unit sphere's points, with H near 1 (the staircase's estimate and the regularized one).
  const radius = Math.hypot(...hit.position);
  check(radius > 0.8 && radius < 1.2, `pick: position ${hit.position} is not on the unit sphere (|p| = ${radius})`);
  check(hit.value > 0.3 && hit.value < 3, `pick: H = ${hit.value} at a point of the unit sphere (expected about 1)`);
  log(`pick at the centre: ${JSON.stringify(hit)}`);

  // 4. setField: no field (plain grey) changes the colours, not the coverage; H again gives the first frame.
  await call("setField", null);
  const none = await measure(await shot("field-none"), bg, first);
  log(`setField(null): ${pct(none.changed)} of the covered pixels changed, coverage ${pct(none.coverage)}`);
  check(none.changed > 0.3, `setField(null) changed only ${pct(none.changed)} of the covered pixels (expected > 30 %)`);
  check(Math.abs(none.coverage - m0.coverage) < 0.2 * m0.coverage, `setField(null) changed the coverage from ${pct(m0.coverage)} to ${pct(none.coverage)}`);
  const hitNone = await pick(...centre);
  check(hitNone && hitNone.value === null, `pick with no field shown: expected value null, got ${JSON.stringify(hitNone)}`);
  await call("setField", "displacement");
  const disp = await measure(await shot("field-displacement"), bg, first);
  check(disp.changed > 0.3, `setField("displacement") changed only ${pct(disp.changed)} of the covered pixels from H's (expected > 30 %)`);
  await call("setField", "H");
  const back = await measure(await shot("field-H"), bg, first);
  check(back.changed < 0.02, `setField("H") did not give the first frame back (${pct(back.changed)} of the pixels differ)`);

  // 5. setLayout("side"): the two spheres side by side, wider than high, one mesh on each side.
  await call("setLayout", "side");
  const sideShot = await shot("side");
  const side = await measure(sideShot, bg);
  const aspect = (m) => (m.bbox.x1 - m.bbox.x0 + 1) / (m.bbox.y1 - m.bbox.y0 + 1);
  log(`side by side: coverage ${pct(side.coverage)}, bbox ${JSON.stringify(side.bbox)}, aspect ${aspect(side).toFixed(2)} (overlay ${aspect(m0).toFixed(2)})`);
  check(side.bbox && aspect(side) > 1.5 * aspect(m0), `setLayout("side"): the covered part is ${aspect(side).toFixed(2)} times as wide as high, overlay ${aspect(m0).toFixed(2)}: expected the meshes side by side`);
  const sx = (f) => (side.bbox.x0 + f * (side.bbox.x1 - side.bbox.x0)) * (canvasBox.width / side.w);
  const sy = ((side.bbox.y0 + side.bbox.y1) / 2) * (canvasBox.height / side.h);
  const left = await pick(sx(0.25), sy), right = await pick(sx(0.75), sy);
  check(left && right && meshIndex(left) >= 0 && meshIndex(right) >= 0 && meshIndex(left) !== meshIndex(right),
    `side by side: pick at the left and right spheres gave ${JSON.stringify(left)} and ${JSON.stringify(right)}: expected one mesh each`);
  // Hiding one: side by side, the other takes the whole picture, as overlaid (the visible meshes are
  // placed and framed again); the hidden one is not picked.
  const hidden = meshIndex(right), kept = meshIndex(left);
  await call("setVisible", hidden, false);
  const one = await measure(await shot("side-one-hidden"), bg);
  log(`side by side, mesh ${hidden} hidden: coverage ${pct(one.coverage)} (both: ${pct(side.coverage)}), aspect ${aspect(one).toFixed(2)}`);
  check(one.coverage > 1.5 * side.coverage && aspect(one) < 0.7 * aspect(side),
    `side by side, hiding mesh ${hidden}: coverage ${pct(side.coverage)} -> ${pct(one.coverage)}, aspect ${aspect(side).toFixed(2)} -> ${aspect(one).toFixed(2)}: expected the other alone, framed larger`);
  const alone = await pick(...centre);
  check(alone && meshIndex(alone) === kept, `side by side, mesh ${hidden} hidden: pick at the centre gave ${JSON.stringify(alone)}, expected mesh ${kept}`);
  await call("setVisible", hidden, true);
  const again = await measure(await shot("side-again"), bg, sideShot);
  check(again.changed < 0.02, `side by side, showing mesh ${hidden} again did not give the side-by-side frame back (${pct(again.changed)} of the pixels differ)`);
  await call("setLayout", "overlay");
  const overlay = await measure(await shot("overlay-again"), bg, first);
  check(overlay.changed < 0.02, `setLayout("overlay") did not give the first frame back (${pct(overlay.changed)} of the pixels differ)`);

  // 6. Shading and wireframe change the picture; flat and smooth differ on the staircase.
  await call("setShading", "flat");
  const flat = await shot("shading-flat");
  await call("setShading", "smooth");
  const smoothShot = await shot("shading-smooth");
  const smooth = await measure(smoothShot, bg, flat);
  check(smooth.changed > 0.02, `setShading: flat and smooth differ in only ${pct(smooth.changed)} of the covered pixels`);
  await call("setWireframe", true);
  const wire = await measure(await shot("wireframe"), bg, smoothShot);
  check(wire.changed > 0.05, `setWireframe(true) changed only ${pct(wire.changed)} of the covered pixels`);
  await call("setWireframe", false);

  // 7. The page regularize wrote: side by side at load.
  const regularizePage = await openPage(join(meshDir, "view.html"));
  const regularizeApi = await regularizePage.page.evaluate(() => ({ fields: window.corrlapView.fields, meshes: window.corrlapView.meshes }));
  check(regularizeApi.meshes.length === 2 && regularizeApi.fields.includes("H"),
    `${meshDir}/view.html: expected 2 meshes and H, got ${JSON.stringify(regularizeApi)}`);
  log(`regularize's view.html ready in ${regularizePage.loadMs.toFixed(0)} ms`);

  // No request but the pages themselves (data: and blob: URLs are a page's own bytes, not I/O).
  const foreign = requests.filter((r) => r.url.split("#")[0] !== r.page && !r.url.startsWith("data:") && !r.url.startsWith("blob:"));
  check(foreign.length === 0, `requests other than the page's own file:\n  ${foreign.map((r) => `${r.page}: ${r.url}`).join("\n  ")}`);
  check(problems.length === 0, `the page reported:\n  ${problems.join("\n  ")}`);
  log(`passed (${requests.length} requests: ${[...new Set(requests.map((r) => r.url.split(":")[0]))].join(", ")}); screenshots in ${scratch}`);
  status = 0;
} catch (e) {
  if (e instanceof Failure) console.error(`FAILED: ${e.message}`);
  else console.error(`FAILED: ${e && e.stack ? e.stack : e}`);
  if (problems.length && !(e instanceof Failure && e.message.includes(problems[0]))) console.error(`the page also reported:\n  ${problems.join("\n  ")}`);
} finally {
  if (browser) await browser.close().catch(() => {});
}
process.exit(status);
