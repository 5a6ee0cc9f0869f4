// Drives OUT/replay.html in headless Chromium (playwright-core from web/node_modules, Debian's
// chromium): waits for the viewer, moves the time slider with the keyboard as a user would,
// takes screenshots, presses Play, presses "closest approach", and prints one JSON line: per
// screenshot the slider label, the number of part triangles coloured as covered and the canvas's
// pixel statistics (mean, spread, a hash), the frame before and after playing, the frame and red
// note the closest approach shows, and any page errors. test_replay checks them.
//   node replay_test.mjs REPLAY.html OUTDIR
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const { chromium } = require(`${process.env.SCANPLAN_WEB_MODULES}/playwright-core`);
const [file, out] = process.argv.slice(2);

const browser = await chromium.launch({
  executablePath: process.env.SCANPLAN_CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync',
    '--enable-unsafe-swiftshader'],
});
const page = await browser.newPage({ viewport: { width: 1000, height: 700 } });
const errors = [];
page.on('pageerror', (e) => errors.push(String(e)));
page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
await page.goto(`file://${file}`);
await page.waitForFunction(() => window.scanplanReplay && window.scanplanReplay.ready, null,
  { timeout: 120000 });

const canvasStats = () => page.evaluate(() => {
  const c = document.querySelector('#view canvas');
  const t = document.createElement('canvas');
  t.width = c.width; t.height = c.height;
  const g = t.getContext('2d');
  g.drawImage(c, 0, 0);
  const d = g.getImageData(0, 0, t.width, t.height).data;
  let sum = 0, sum2 = 0, n = 0, hash = 0;
  for (let i = 0; i < d.length; i += 4) {
    const v = (d[i] + d[i + 1] + d[i + 2]) / 3;
    sum += v; sum2 += v * v; ++n;
    hash = (Math.imul(hash, 31) + d[i] * 65536 + d[i + 1] * 256 + d[i + 2]) >>> 0;
  }
  const mean = sum / n;
  return { mean, spread: Math.sqrt(Math.max(0, sum2 / n - mean * mean)), hash };
});
const shot = async (name) => {
  await page.screenshot({ path: `${out}/${name}.png` });
  return { name, label: await page.textContent('#label'),
    frame: await page.evaluate(() => window.scanplanReplay.frame),
    coloured: await page.evaluate(() => window.scanplanReplay.coloured()),
    ...(await canvasStats()) };
};

const shots = [];
await page.focus('#time');
await page.keyboard.press('Home');
shots.push(await shot('replay_start'));
for (let i = 0; i < 5; ++i) await page.keyboard.press('PageUp');
shots.push(await shot('replay_middle'));
await page.keyboard.press('End');
shots.push(await shot('replay_end'));
await page.keyboard.press('Home');
const before = await page.evaluate(() => window.scanplanReplay.frame);
await page.click('#play');
// Software WebGL draws a frame in up to a second or two, longer on a loaded machine: poll for the
// motion every 100 ms for up to 60 s, not a fixed time.
for (const deadline = Date.now() + 60000; Date.now() < deadline;) {
  if (await page.evaluate(() => window.scanplanReplay.frame) > 0) break;
  await page.waitForTimeout(100);
}
await page.click('#play');
const after = await page.evaluate(() => window.scanplanReplay.frame);
await page.click('#closest');
const closest = { frame: await page.evaluate(() => window.scanplanReplay.frame),
  note: await page.textContent('#note') };
console.log(JSON.stringify({ shots, before, after, closest, frames:
  await page.evaluate(() => window.scanplanReplay.frames), errors }));
await browser.close();
