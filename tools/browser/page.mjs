// Opens a page in headless Chromium (Debian's, with WebGPU on SwiftShader) and prints
// one JSON line.
//
//   node tools/browser/page.mjs http://127.0.0.1:PORT/index.html?size=WxH OUT.rgba
//     an exported scene (`sdfc export-web`): the WGSL compiler's messages, the page's
//     error if any, the frame's size; its first frame's pixels (RGBA, rows top first,
//     read from the canvas's own texture in the frame that draws it) go to OUT.rgba.
//   node tools/browser/page.mjs live http://127.0.0.1:PORT/?size=WxH DIR
//     a page served by `sdfc serve`: waits for its first build, then for each line on
//     standard input, a JavaScript condition on the page (`window.sdfcGeneration > 1`,
//     `window.sdfcDiagnostics`), waits until it holds; after the first build and after
//     each condition it writes the canvas's pixels to DIR/K.rgba (K = 0, 1, …) and
//     prints a JSON line: generation, diagnostics, the overlay's and the status's text,
//     the compiler's messages, the console so far. Ends at the end of its input.
//   node tools/browser/page.mjs http://127.0.0.1:PORT/check.html
//     the module check (check.js): every listed module compiled by Tint and every
//     pipeline built from the manifest's users under default limits.
//
// The flags are the ones WebGPU needs headless on a machine without a GPU; the page
// must come from http://127.0.0.1 (a secure context).
import puppeteer from "puppeteer-core";

import { writeFileSync } from "node:fs";
import { createInterface } from "node:readline";

const live = process.argv[2] === "live";
const [url, rawOut] = process.argv.slice(live ? 3 : 2);
const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: "new",
  // A waitForFunction below is one protocol call for as long as it waits: past
  // puppeteer's default protocol timeout (180 s) it failed before its own 240 s, on a
  // slow machine running the rest of the suite beside it.
  protocolTimeout: 300000,
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
  if (live) {
    // Each report is printed as it comes.
    await follow(page, console);
    out = { done: true };
  } else {
    await page.waitForFunction("window.sdfcReady || window.sdfcError", { timeout: 240000 });
    if (url.includes("check.html")) {
      out = await page.evaluate("window.sdfcCheck || { error: window.sdfcError }");
      out.console = console;
    } else {
      out = await scene(page, console);
    }
  }
} finally {
  // The page has said what it was asked, so the browser is killed rather than closed:
  // on the 2-core machine Chromium's orderly exit made each exported page 0.4-1.2 s
  // slower (7.0-7.3 s against 6.1-6.7 s), and 3.4-4.3 s, with a core busy, while a page
  // still drew. Its other processes exit with it, and puppeteer removes its temporary
  // profile when the process ends.
  browser.process().kill("SIGKILL");
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
      pixels = await page.evaluate("window.sdfcPixels(false)");
    } catch (e) {
      readError = String(e);
    }
  }
  const size = await page.evaluate(
    "[document.getElementById('scene').width, document.getElementById('scene').height]",
  );
  if (pixels && rawOut) writeFileSync(rawOut, Buffer.from(pixels, "base64"));
  // With SDFC_PAGE_INPUT=1, real mouse input on the canvas (puppeteer's input events):
  // a drag to turn, then the wheel to zoom; the frame after each goes to
  // OUT.rgba.drag and OUT.rgba.wheel.
  if (!error && rawOut && process.env.SDFC_PAGE_INPUT === "1") {
    const box = await (await page.$("#scene")).boundingBox();
    const [cx, cy] = [box.x + box.width / 2, box.y + box.height / 2];
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    await page.mouse.move(cx + box.width / 4, cy, { steps: 8 });
    await page.mouse.up();
    await new Promise((r) => setTimeout(r, 500));
    const dragged = await page.evaluate("window.sdfcPixels(false)");
    writeFileSync(`${rawOut}.drag`, Buffer.from(dragged, "base64"));
    await page.mouse.move(cx, cy);
    await page.mouse.wheel({ deltaY: -300 });
    await new Promise((r) => setTimeout(r, 500));
    const zoomed = await page.evaluate("window.sdfcPixels(false)");
    writeFileSync(`${rawOut}.wheel`, Buffer.from(zoomed, "base64"));
    // The first parameter's slider, clicked near its right end.
    const slider = await page.$("#params input[type=range]");
    if (slider) {
      const s = await slider.boundingBox();
      await page.mouse.click(s.x + s.width - 3, s.y + s.height / 2);
      await new Promise((r) => setTimeout(r, 500));
      const slid = await page.evaluate("window.sdfcPixels(false)");
      writeFileSync(`${rawOut}.slider`, Buffer.from(slid, "base64"));
    }
  }
  return { error: error || readError, messages, console, size };
}

/// The live mode: a report after the first build and after each condition read from
/// standard input.
async function follow(page, console) {
  const lines = createInterface({ input: process.stdin })[Symbol.asyncIterator]();
  let condition = "window.sdfcGeneration > 0 || window.sdfcError";
  for (let k = 0; ; k++) {
    await page.waitForFunction(condition, { timeout: 240000 });
    const error = await page.evaluate("window.sdfcError || null");
    let pixels = null;
    if (!error) pixels = await page.evaluate("window.sdfcPixels(false)");
    if (pixels) writeFileSync(`${rawOut}/${k}.rgba`, Buffer.from(pixels, "base64"));
    const report = await page.evaluate(`({
      generation: window.sdfcGeneration,
      diagnostics: window.sdfcDiagnostics,
      overlay: document.getElementById("diagnostics").hidden ? null
        : document.getElementById("diagnostics").textContent,
      status: document.getElementById("status").textContent,
      messages: window.sdfcMessages || [],
      sliders: [...document.querySelectorAll("#params label")].map((l) => l.textContent),
    })`);
    process.stdout.write(JSON.stringify({ ...report, error, console, pixels: !!pixels }) + "\n");
    const next = await lines.next();
    if (next.done) return;
    condition = next.value;
  }
}
