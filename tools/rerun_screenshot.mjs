// A screenshot of a rerun recording in rerun's web viewer, in headless Chromium: what a user sees
// when the recording opens (docs/rerun-viewer.png).
//
//   softhand handshake --record /tmp/hs.rrd
//   rerun --serve-web --web-viewer-port 9090 --port 9876 /tmp/hs.rrd &
//   npm install @sparticuz/chromium puppeteer-core   # a Chromium build shipped in the npm package
//   node tools/rerun_screenshot.mjs docs/rerun-viewer.png [seconds after opening, default 10]
//
// WebGL runs on Chromium's software rasterizer (SwiftShader): the viewer says so in its top bar.
import chromium from "@sparticuz/chromium";
import puppeteer from "puppeteer-core";

const [out = "rerun-viewer.png", wait = "10"] = process.argv.slice(2);
const browser = await puppeteer.launch({
  executablePath: await chromium.executablePath(),
  args: [...chromium.args, "--enable-unsafe-swiftshader"],
  headless: true,
  defaultViewport: { width: 1600, height: 1000 },
});
try {
  const page = await browser.newPage();
  const proxy = encodeURIComponent("rerun+http://127.0.0.1:9876/proxy");
  await page.goto(`http://127.0.0.1:9090/?url=${proxy}&renderer=webgl`,
                  { waitUntil: "load", timeout: 60000 });
  await new Promise((r) => setTimeout(r, Number(wait) * 1000));
  await page.screenshot({ path: out });
  console.log(`wrote ${out}`);
} finally {
  await browser.close();
}
