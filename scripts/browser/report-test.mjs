// The browser test of report.html (run by scripts/browser-test.sh): each output folder given
// is opened from disk in headless chromium (Debian's, through playwright-core), and the page
// must load with no network request, draw its 3-D view (pixels that are not background), move
// its UAVs when scrubbed to where trajectories.csv has them at that time, list every UAV id,
// and play. A screenshot of each is kept in the folder given by --shots.
import { chromium } from "playwright-core";
import fs from "node:fs";
import path from "node:path";

const args = process.argv.slice(2);
let shots = "target/browser-test";
const dirs = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--shots") shots = args[++i];
  else dirs.push(args[i]);
}
fs.mkdirSync(shots, { recursive: true });
const failures = [];
const check = (ok, what) => {
  if (!ok) failures.push(what);
  console.log((ok ? "ok   " : "FAIL ") + what);
};

// trajectories.csv: time (as written) → UAV → [x, y, z].
const trajectories = (file) => {
  const lines = fs.readFileSync(file, "utf8").trim().split("\n");
  const head = lines[0].split(",");
  const [it, iu, ix, iy, iz] = ["t_s", "uav", "x_m", "y_m", "z_m"].map((c) => head.indexOf(c));
  const out = new Map();
  for (const line of lines.slice(1)) {
    const c = line.split(",");
    const t = parseFloat(c[it]);
    if (!out.has(t)) out.set(t, new Map());
    out.get(t).set(parseInt(c[iu], 10), [parseFloat(c[ix]), parseFloat(c[iy]), parseFloat(c[iz])]);
  }
  return out;
};

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  args: [
    "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
  ],
});
try {
  for (const dir of dirs) {
    const name = path.basename(path.resolve(dir));
    const page = await browser.newPage({ viewport: { width: 1100, height: 1600 } });
    const requests = [];
    const errors = [];
    page.on("request", (r) => requests.push(r.url()));
    page.on("pageerror", (e) => errors.push(String(e)));
    page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
    const url = "file://" + path.resolve(dir, "report.html");
    await page.goto(url);
    await page.waitForFunction(() => window.proxform && window.proxform.ready, null, { timeout: 30000 });
    check(errors.length === 0, `${name}: no script error (${errors.join("; ")})`);
    const outside = requests.filter((u) => u !== url);
    check(outside.length === 0, `${name}: no request beyond the page itself (${outside.slice(0, 5).join(", ")})`);
    check(await page.evaluate(() => window.proxform.webgl), `${name}: WebGL available`);
    const pixels = await page.evaluate(() => window.proxform.drawnPixels());
    check(pixels > 2000, `${name}: the 3-D view is drawn (${pixels} pixels not background)`);

    // Scrubbing: the page's positions at a time are trajectories.csv's at that time.
    const csv = trajectories(path.join(dir, "trajectories.csv"));
    const times = await page.evaluate(() => window.proxform.times());
    const picks = [Math.floor(times.length / 4), Math.floor(times.length / 2), times.length - 1].map((i) => times[i]);
    let before = null, moved = false;
    for (const t of picks) {
      const at = await page.evaluate((t) => window.proxform.seek(t), t);
      const shown = await page.evaluate(() => window.proxform.positions());
      const rows = csv.get(at);
      check(rows !== undefined, `${name}: t = ${at} s is a time of trajectories.csv`);
      if (!rows) continue;
      let worst = 0, count = 0;
      for (const [uav, p] of rows) {
        const q = shown[uav];
        if (!q) { worst = Infinity; continue; }
        count++;
        worst = Math.max(worst, Math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]));
      }
      check(count === rows.size && worst < 1e-6, `${name}: at t = ${at} s every UAV where trajectories.csv has it (${count} of ${rows.size}, off by ${worst} m at most)`);
      if (before) moved ||= Object.keys(shown).some((u) => before[u] && Math.hypot(...shown[u].map((v, k) => v - before[u][k])) > 0.1);
      before = shown;
    }
    check(moved, `${name}: scrubbing moves the UAVs`);
    const pixelsLater = await page.evaluate(() => window.proxform.drawnPixels());
    check(pixelsLater > 2000, `${name}: still drawn after scrubbing (${pixelsLater} pixels)`);

    // Every UAV listed: the per-UAV table has each of summary.json's, and the navigator.
    const summary = JSON.parse(fs.readFileSync(path.join(dir, "summary.json"), "utf8"));
    const listed = await page.evaluate(() => [...document.querySelectorAll("#uavs tr[data-uav]")].map((r) => parseInt(r.dataset.uav, 10)));
    const missing = summary.per_uav.filter((u) => !listed.includes(u));
    check(missing.length === 0 && listed.length === summary.uavs, `${name}: every UAV listed (${listed.length} of ${summary.uavs}; missing ${missing.slice(0, 5)})`);

    // Play: time goes on.
    await page.evaluate(() => { window.proxform.seek(0); window.proxform.play(); });
    await page.waitForTimeout(1200);
    const played = await page.evaluate(() => { const t = window.proxform.time(); window.proxform.pause(); return t; });
    check(played > 0, `${name}: playing moves the time on (t = ${played} s after 1.2 s)`);

    await page.evaluate((t) => window.proxform.seek(t), picks[1]);
    const shot = path.join(shots, `report-${name}.png`);
    await page.screenshot({ path: shot, fullPage: true });
    console.log(`     screenshot ${shot}`);
    await page.close();
  }
} finally {
  await browser.close();
}
if (failures.length) {
  console.error(`browser test: ${failures.length} check(s) failed`);
  process.exit(1);
}
console.log("browser test: every check passed");
