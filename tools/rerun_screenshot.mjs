// A screenshot of a handshake recording in rerun's web viewer, in headless Chromium, at mid-shake
// (docs/rerun-viewer.png).
//
//   softhand handshake --record /tmp/hs.rrd
//   npm install @sparticuz/chromium puppeteer-core   # a Chromium build shipped in the npm package
//   node tools/rerun_screenshot.mjs /tmp/hs.rrd docs/rerun-viewer.png
//
// The tool serves the recording itself (`python3 -m rerun --serve-web`, ports 9090 and 9876; set
// PYTHON to the interpreter that has softhand and rerun-sdk), waits for the viewer to load it, then
// pauses the playback and types the middle of the shake into the time panel's time field: the time
// comes from the recording (softhand.viz.recording.mid_shake_s: halfway through the partner's
// `shake` phase), so the picture no longer depends on how long the page took to load. A rerun
// blueprint cannot place the time cursor (rerun-sdk 0.41), hence the clicks; their positions are
// those of rerun 0.41's layout in the 1600 x 1000 viewport below.
//
// WebGL runs on Chromium's software rasterizer (SwiftShader): the viewer says so in its top bar.
import { execFileSync, spawn } from "node:child_process";
import chromium from "@sparticuz/chromium";
import puppeteer from "puppeteer-core";

const [rrd, out = "rerun-viewer.png"] = process.argv.slice(2);
if (!rrd || !rrd.endsWith(".rrd")) {
  console.error("usage: node tools/rerun_screenshot.mjs RECORDING.rrd [OUT.png]");
  process.exit(2);
}
const python = process.env.PYTHON || "python3";
const sleep = (s) => new Promise((r) => setTimeout(r, s * 1000));
const atS = Number(execFileSync(python, ["-c",
  "import sys; from softhand.viz.recording import mid_shake_s; print(mid_shake_s(sys.argv[1]))",
  rrd]).toString().trim());
console.log(`mid-shake: t = ${atS.toFixed(3)} s`);

const server = spawn(python, ["-m", "rerun", "--serve-web", "--web-viewer-port", "9090",
                              "--port", "9876", rrd], { stdio: "ignore", detached: true });
const PAUSE = { x: 26, y: 864 };       // the time panel's play/pause button
const TIME_FIELD = { x: 392, y: 864 }; // the time panel's current-time field
let browser;
try {
  for (let i = 0; ; i++) {  // until the web viewer answers (at most 30 s)
    try { if ((await fetch("http://127.0.0.1:9090/")).ok) break; } catch {}
    if (i === 60) throw new Error("rerun's web viewer did not start on port 9090");
    await sleep(0.5);
  }
  browser = await puppeteer.launch({
    executablePath: await chromium.executablePath(),
    args: [...chromium.args, "--enable-unsafe-swiftshader"],
    headless: true,
    defaultViewport: { width: 1600, height: 1000 },
  });
  const page = await browser.newPage();
  const proxy = encodeURIComponent("rerun+http://127.0.0.1:9876/proxy");
  await page.goto(`http://127.0.0.1:9090/?url=${proxy}&renderer=webgl`,
                  { waitUntil: "load", timeout: 60000 });
  await sleep(8);  // the recording streams in; the time shown no longer depends on this wait
  await page.mouse.click(PAUSE.x, PAUSE.y);
  await sleep(1);
  await page.mouse.click(TIME_FIELD.x, TIME_FIELD.y);
  await page.keyboard.down("Control");
  await page.keyboard.press("KeyA");
  await page.keyboard.up("Control");
  await page.keyboard.type(`${atS.toFixed(3)}s`);
  await page.keyboard.press("Enter");
  await sleep(5);  // software WebGL redraws the views at the new time
  await page.screenshot({ path: out });
  console.log(`wrote ${out} (t = ${atS.toFixed(3)} s)`);
} finally {
  if (browser) await browser.close();
  process.kill(-server.pid);  // its process group: `python -m rerun` runs the viewer as a child
}
