// Size and load time of the page `corrlap view` writes (viewer/README.md), for meshes of about 100K
// and 1M faces: the unit sphere digitized by the CLI, without a field (`digitize`) and with the
// eight fields of `curvature` (G, H, k1, k2 per vertex and per face; H shown). Load time: navigation
// start to `corrlapView.ready` (the first frame drawn) in headless Chromium, WebGL on SwiftShader
// (the CPU; a GPU is faster), median of --repeat fresh pages. Results in bench/RESULTS.md ("Viewer").
//
//     node bench/viewer_load.mjs [--corrlap build/bin/corrlap] [--node-modules build/viewer/node_modules]
//         [--out DIR] [--repeat 3] [--sizes 100k,1m]
// --out keeps the meshes and pages (about 750 MB with 1m) in DIR; without it they go to a temporary
// folder, removed at the end.
// Chromium: $CHROMIUM, else /usr/bin/chromium (scripts/install_deps.sh --chromium).
import { execFileSync } from "node:child_process";
import { closeSync, mkdirSync, mkdtempSync, openSync, readSync, rmSync, statSync } from "node:fs";
import { createRequire } from "node:module";
import { tmpdir } from "node:os";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const root = resolve(dirname(fileURLToPath(import.meta.url)), "..");
const opts = { corrlap: join(root, "build/bin/corrlap"), "node-modules": join(root, "build/viewer/node_modules"),
  out: null, repeat: "3", sizes: "100k,1m" };
const argv = process.argv.slice(2);
for (let i = 0; i < argv.length; i += 2) {
  const key = argv[i].replace(/^--/, "");
  if (!(key in opts) || argv[i + 1] === undefined) {
    console.error(`viewer_load.mjs: bad option ${argv[i]} (known: ${Object.keys(opts).map((k) => "--" + k).join(", ")})`);
    process.exit(2);
  }
  opts[key] = argv[i + 1];
}
const repeat = Number(opts.repeat);
// Grid steps giving about 100K and 1M faces on the unit sphere (faces ~ 18.8 / h^2).
const steps = { "100k": 0.0137, "1m": 0.00434 };
const sizes = opts.sizes.split(",");
for (const s of sizes) if (!(s in steps)) throw new Error(`--sizes: ${s}? (known: ${Object.keys(steps)})`);
const out = opts.out ? resolve(opts.out) : mkdtempSync(join(tmpdir(), "corrlap-viewer-load-"));
mkdirSync(out, { recursive: true });

const playwright = createRequire(join(resolve(opts["node-modules"]), "package.json"))("playwright-core");
const chromiumPath = process.env.CHROMIUM || "/usr/bin/chromium";

function run(args) {
  const t = process.hrtime.bigint();
  execFileSync(opts.corrlap, args, { stdio: ["ignore", "ignore", "inherit"] });
  return Number(process.hrtime.bigint() - t) / 1e9;
}
function headerOf(ply) {
  const fd = openSync(ply, "r"), head = Buffer.alloc(4096);
  const n = readSync(fd, head, 0, head.length, 0);
  closeSync(fd);
  return head.subarray(0, n).toString("latin1");
}
const median = (a) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];
const mb = (bytes) => (bytes / 1e6).toFixed(1);

// The pages.
const cases = [];
for (const size of sizes) {
  const h = String(steps[size]);
  const dir = join(out, size);
  mkdirSync(dir, { recursive: true });
  const bare = join(dir, "digitized.ply");
  run(["digitize", "--shape", "sphere1", "--h", h, "--out", bare]);
  run(["curvature", "--shape", "sphere1", "--h", h, "--radius", String(3.5 * steps[size]), "--out", join(dir, "curvature")]);
  const fielded = join(dir, "curvature", "curvature.ply");
  for (const [label, ply, scalar] of [["no field", bare, "none"], ["8 fields", fielded, "H"]]) {
    const page = join(dir, `${label.replace(" ", "-")}.html`);
    const write = run(["view", ply, "--scalar", scalar, "--out", page]);
    const faces = Number(/element face (\d+)/.exec(headerOf(ply))[1]);
    cases.push({ size, label, ply, page, faces, write });
  }
}

// The loads.
const browser = await playwright.chromium.launch({ executablePath: chromiumPath, headless: true,
  args: ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"] });
const version = browser.version();
const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, deviceScaleFactor: 1 });
// One load of the first page first, not counted: the browser's first page starts its GPU process
// and compiles the script, a second or so that a reader opening a page in a running browser does not wait.
const warmUp = { ready: [], parsed: [], page: cases[0].page };
for (const c of [warmUp, ...cases]) {
  c.ready = [];
  c.parsed = [];
  for (let r = 0; r < (c === warmUp ? 1 : repeat); r++) {
    const page = await context.newPage();
    const errors = [];
    page.on("pageerror", (e) => errors.push(e.message));
    await page.goto(pathToFileURL(c.page).href, { waitUntil: "commit", timeout: 120000 });
    // performance.now() counts from the navigation's start.
    const t = await page.evaluate(() => new Promise((done, fail) => {
      const wait = () => {
        if (!window.corrlapView) return setTimeout(wait, 5);
        window.corrlapView.ready.then(() => {
          const now = performance.now();
          const nav = performance.getEntriesByType("navigation")[0];
          done({ ready: now, parsed: nav ? nav.domContentLoadedEventStart : NaN });
        }, (e) => fail(new Error(String(e && e.message ? e.message : e))));
      };
      wait();
    }));
    if (errors.length) throw new Error(`${c.page}: ${errors.join("; ")}`);
    c.ready.push(t.ready);
    c.parsed.push(t.parsed);
    await page.close();
  }
}
await browser.close();

console.log(`corrlap view pages in headless Chromium ${version} (${chromiumPath}, WebGL on SwiftShader, 1280 x 800), ` +
  `${repeat} loads each${opts.out ? `; files in ${out}` : ""}`);
console.log("| mesh | faces | PLY (MB) | page (MB) | corrlap view (s) | DOMContentLoaded (s) | ready (s): median (min-max) |");
console.log("|---|---:|---:|---:|---:|---:|---:|");
for (const c of cases) {
  console.log(`| sphere1 h=${steps[c.size]}, ${c.label} | ${c.faces} | ${mb(statSync(c.ply).size)} | ${mb(statSync(c.page).size)} | ` +
    `${c.write.toFixed(2)} | ${(median(c.parsed) / 1000).toFixed(2)} | ${(median(c.ready) / 1000).toFixed(2)} ` +
    `(${(Math.min(...c.ready) / 1000).toFixed(2)}-${(Math.max(...c.ready) / 1000).toFixed(2)}) |`);
}
console.log(`The first page in the fresh browser (not in the table, the first row's page): ready after ${(warmUp.ready[0] / 1000).toFixed(2)} s.`);
if (!opts.out) rmSync(out, { recursive: true, force: true });
