// Opens a page in headless Chromium (Debian's, with WebGPU on SwiftShader) and prints
// one JSON line.
//
//   node tools/browser/page.mjs http://127.0.0.1:PORT/index.html?size=WxH OUT.rgba
//     an exported scene (`sdfc export-web`): the WGSL compiler's messages, the page's
//     error if any, the frame's size; its first frame's pixels (RGBA, rows top first,
//     rendered offscreen by the page's own pipeline) go to OUT.rgba.
//   node tools/browser/page.mjs http://127.0.0.1:PORT/check.html
//     the module check (check.js): every listed module compiled by Tint and every
//     pipeline built from the manifest's users under default limits.
//
// The flags are the ones WebGPU needs headless on a machine without a GPU; the page
// must come from http://127.0.0.1 (a secure context).
import puppeteer from "puppeteer-core";

import { writeFileSync } from "node:fs";

const [url, rawOut] = process.argv.slice(2);
const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: "new",
  dumpio: !!process.env.SDFC_BROWSER_LOG,
  args: [
    "--headless=new",
    "--enable-unsafe-webgpu",
    "--enable-features=Vulkan,WebGPU",
    "--use-webgpu-adapter=swiftshader",
    "--use-angle=swiftshader",
    "--use-vulkan=swiftshader",
    "--enable-unsafe-swiftshader",
    "--no-sandbox",
    "--disable-gpu-sandbox",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
  ],
});
let out;
try {
  const page = await browser.newPage();
  const console = [];
  page.on("console", (m) => console.push(`${m.type()}: ${m.text()}`));
  page.on("pageerror", (e) => console.push(`pageerror: ${e.message}`));
  await page.goto(url, { waitUntil: "load" });
  await page.waitForFunction("window.sdfcReady || window.sdfcError", { timeout: 240000 });
  if (url.includes("check.html")) {
    out = await page.evaluate("window.sdfcCheck || { error: window.sdfcError }");
    out.console = console;
  } else {
    out = await scene(page, console);
  }
} finally {
  await browser.close();
}
process.stdout.write(JSON.stringify(out) + "\n");

/// An exported scene's messages and first frame.
async function scene(page, console) {
  const error = await page.evaluate("window.sdfcError || null");
  const messages = await page.evaluate("window.sdfcMessages || []");
  let pixels = null;
  let readError = null;
  if (!error) {
    try {
      pixels = await page.evaluate("window.sdfcPixels(true)");
    } catch (e) {
      readError = String(e);
    }
  }
  const size = await page.evaluate(
    "[document.getElementById('scene').width, document.getElementById('scene').height]",
  );
  if (pixels && rawOut) writeFileSync(rawOut, Buffer.from(pixels, "base64"));
  return { error: error || readError, messages, console, size };
}
