// Loads polarslam-bridge's built-in page in headless Chromium (puppeteer-core, Debian's
// /usr/bin/chromium), waits until it has drawn a grid, counts the canvas pixels the map covers
// (free cells light, occupied ones dark) and clicks the middle of the canvas, which should send
// a GOAL at the middle of the grid (the page fits the grid to the canvas).
//   node page_test.mjs --url http://127.0.0.1:8765/ [--chromium /usr/bin/chromium] [--timeout 30]
// Prints one JSON summary line; exit code 0 = the map was drawn and the click was made.
import puppeteer from "puppeteer-core";

function option(name, fallback) {
  const at = process.argv.indexOf("--" + name);
  return at > 0 ? process.argv[at + 1] : fallback;
}
const url = option("url", "http://127.0.0.1:8765/");
const chromium = option("chromium", "/usr/bin/chromium");
const timeoutMs = Number(option("timeout", "30")) * 1000;

const summary = { ok: false, failures: [] };
const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--no-first-run", "--no-proxy-server"],
});
try {
  const page = await browser.newPage();
  page.on("pageerror", (error) => summary.failures.push("page error: " + error.message));
  await page.setViewport({ width: 1600, height: 900 });
  await page.goto(url, { waitUntil: "load", timeout: timeoutMs });
  await page.waitForFunction(() => window.polarslamPage?.received?.GRID_MAP > 0 && window.polarslamPage.view,
    { timeout: timeoutMs, polling: 100 });
  await page.waitForFunction(() => !window.polarslamPage.dirty, { timeout: timeoutMs, polling: 50 });
  Object.assign(summary, await page.evaluate(() => {
    const canvas = document.getElementById("map");
    const pixels = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
    let drawn = 0, light = 0, dark = 0;
    for (let i = 0; i < pixels.length; i += 4) {
      if (pixels[i + 3] === 0) continue;  // nothing drawn: the page background shows
      drawn += 1;
      if (pixels[i] > 200) light += 1;
      if (pixels[i] < 60) dark += 1;
    }
    return { canvasPixels: canvas.width * canvas.height, drawn, light, dark, canPublish: window.polarslamPage.canPublish };
  }));
  const box = await (await page.$("#map")).boundingBox();
  await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
  summary.goal = await page.evaluate(() => window.polarslamPage.goal);
  summary.clicked = true;
  summary.processRows = await page.evaluate(() => document.querySelectorAll("#processes tbody tr").length);
  await new Promise((resolve) => setTimeout(resolve, 500));  // the goal frame leaves before the page closes
} catch (error) {
  summary.failures.push(String(error));
} finally {
  await browser.close();
}
summary.ok = summary.failures.length === 0 && summary.clicked === true;
console.log(JSON.stringify(summary));
process.exit(summary.ok ? 0 : 1);
