// The operator console in a real browser: Debian's chromium, headless,
// driven by puppeteer-core (no browser download), against a paced `rigctl
// run`. Every step waits for what it expects on the page (no fixed sleeps)
// and writes what it saw to --out; screenshots go to --screenshots.
//
//   node console_browser.cjs --url http://127.0.0.1:PORT/ --key HEX --wrong-key HEX
//        --screenshots DIR --out result.json [--scenario commands|trip|channels]
//
// commands: traces update; take control; reset .. start drive the rig to
//   running; a wrong key, a stale and a replayed hold are refused with their
//   reasons and the rig stays as it was; a hold holds it; a second console
//   may hold but neither resume nor take control; malformed messages from a raw
//   client are answered and survived; a console that disconnects right
//   after a command frees control; the first console stops the rig (S key).
// trip: a run whose x_r is at its rail: the trips and the detector table.
// procedure: a run of a block program (rigctl run --procedure): the procedure
//   panel counts; hold, resume and "stop at block end" from the page, the
//   request shown until the block ends and the rig stops there.
// channels: a rig with several control channels (the two-poster): the scope
//   lists every channel's demand, feedback and valve, each demand with its
//   feedback in a strip of its own, and every trace updates.
"use strict";
const fs = require("fs");
const os = require("os");
const path = require("path");
const puppeteer = require("puppeteer-core");
const { malformedClient } = require("./console_malformed.cjs");

const TIMEOUT_MS = 120000;  // a deadline for what never happens, on a loaded 2-core machine
// Waits poll on an interval, not on animation frames: a tab in the
// background (the first console, while the second is in front) gets none.
const POLL = { polling: 100 };

function parseArgs(argv) {
  const args = { scenario: "commands" };
  for (let i = 2; i < argv.length; i += 2) args[argv[i].replace(/^--/, "").replace(/-([a-z])/g, (_, c) => c.toUpperCase())] = argv[i + 1];
  return args;
}

async function launch() {
  const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), "rigctl-chromium-"));
  // Without these flags chromium waits on the network it has not got.
  const browser = await puppeteer.launch({
    executablePath: "/usr/bin/chromium",
    headless: true,
    userDataDir,
    protocolTimeout: TIMEOUT_MS,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
           "--disable-component-update", "--disable-sync"],
  });
  return { browser, userDataDir };
}

async function openConsole(browser, url, log) {
  const page = await browser.newPage();
  page.setDefaultTimeout(TIMEOUT_MS);
  await page.setViewport({ width: 1280, height: 900 });
  page.on("console", (m) => log.push("page: " + m.text()));
  page.on("pageerror", (e) => log.push("page error: " + e.message));
  await page.goto(url, { waitUntil: "load" });
  await page.waitForFunction(() => document.getElementById("connection").textContent === "connected", POLL);
  return page;
}

const state = (page) => page.$eval("#safety-state", (e) => e.textContent);
const waitState = (page, s) => page.waitForFunction((s) => document.getElementById("safety-state").textContent === s, POLL, s);
const samples = (page) => page.$eval("#scope-stats", (e) => Number(e.dataset.samples || 0));

// Waits for the n-th answer to `command` (counting from the oldest) and returns it.
async function answer(page, command, n = 1) {
  await page.waitForFunction((c, n) => document.querySelectorAll(`#answers li[data-command="${c}"]:not([data-reason="pending"])`).length >= n,
                             POLL, command, n);
  return page.$$eval(`#answers li[data-command="${command}"]:not([data-reason="pending"])`,
                     (items, n) => { const e = items[items.length - n]; return { reason: e.dataset.reason, text: e.textContent }; }, n);
}

async function setField(page, selector, value) {
  await page.$eval(selector, (e) => { e.value = ""; });
  await page.type(selector, value);
}

async function tracesUpdate(page, result) {
  await page.waitForFunction(() => Number(document.getElementById("scope-stats").dataset.samples || 0) > 200, POLL);
  const first = await samples(page);
  await page.waitForFunction((n) => Number(document.getElementById("scope-stats").dataset.samples) > n + 400, POLL, first);
  result.samplesSeen = await samples(page);
  result.framesDrawn = await page.evaluate(() => window.rigctlConsole.scope.drawn);
}

// Pause freezes the plot's window, not the record; the window goes to 60 s.
async function pauseAndWindow(page, result) {
  await page.click("#pause");
  const before = await page.evaluate(() => ({ end: window.rigctlConsole.scope.frozenEnd, n: Number(document.getElementById("scope-stats").dataset.samples) }));
  await page.waitForFunction((n) => Number(document.getElementById("scope-stats").dataset.samples) > n + 200, POLL, before.n);
  const after = await page.evaluate(() => ({ end: window.rigctlConsole.scope.frozenEnd, n: Number(document.getElementById("scope-stats").dataset.samples) }));
  await page.click("#pause");
  await page.$eval("#window", (e) => { e.value = "60"; e.dispatchEvent(new Event("input")); });
  result.paused = { endBefore: before.end, endAfter: after.end, samplesBefore: before.n, samplesAfter: after.n,
                    windowS: await page.evaluate(() => window.rigctlConsole.scope.windowS) };
  await page.$eval("#window", (e) => { e.value = "5"; e.dispatchEvent(new Event("input")); });  // for the screenshot
}

async function driveToRunning(page, result) {
  const steps = [["reset", "off"], ["hydraulics_low", "hydraulics_low"], ["hydraulics_high", "hydraulics_high"],
                 ["arm", "armed"], ["start", "running"]];
  for (const [command, to] of steps) {
    await page.click(`#command-buttons button[data-command="${command}"]`);
    result.answers.push({ console: "A", command, ...(await answer(page, command)) });
    await waitState(page, to);
  }
}

// Wrong key, stale, then the right hold and its replay.
async function refusalsAndHold(page, args, result) {
  await setField(page, "#key", args.wrongKey);
  await page.click('#command-buttons button[data-command="hold"]');
  result.wrongKey = await answer(page, "hold", 1);
  result.stateAfterWrongKey = await state(page);
  await setField(page, "#key", args.key);
  await page.evaluate(() => window.rigctlConsole.send("hold", 0, { utimeOffsetUs: -30e6 }));  // signed 30 s ago
  result.stale = await answer(page, "hold", 2);
  result.stateAfterStale = await state(page);
  // The hold, and at once the same bytes again (within the staleness window).
  await page.evaluate(async () => { await window.rigctlConsole.send("hold"); window.rigctlConsole.replayLast(); });
  result.hold = await answer(page, "hold", 3);
  result.replayed = await answer(page, "hold", 4);
  await waitState(page, "holding");
  result.stateAfterHold = await state(page);
  // A held setpoint inside the configured range, then one outside it.
  await setField(page, "#setpoint", "0.02");
  await page.click("#send-setpoint");
  result.setpoint = await answer(page, "setpoint", 1);
  await page.waitForFunction(() => /setpoint 0\.02 accepted/.test(document.getElementById("events").textContent), POLL);
  await setField(page, "#setpoint", "0.5");
  await page.click("#send-setpoint");
  result.setpointOutOfRange = await answer(page, "setpoint", 2);
}

async function secondConsole(browser, args, result, log) {
  const b = await openConsole(browser, args.url, log);
  await setField(b, "#sender", "bob");
  await setField(b, "#key", args.key);
  await b.click("h2");
  await b.keyboard.press("h");  // the hold shortcut, from a console without control: stop and hold need none
  result.secondHold = await answer(b, "hold");
  await b.click('#command-buttons button[data-command="resume"]');
  result.secondResume = await answer(b, "resume");
  await b.click("#take-control");
  result.secondTakeControl = await answer(b, "take_control");
  result.stateAfterSecond = await state(b);
  return b;
}

// A releases; B takes control, sends resume and drops its connection at once.
async function disconnectMidCommand(a, b, result) {
  await a.bringToFront();
  await a.click("#release-control");
  await b.bringToFront();
  await b.waitForFunction(() => document.getElementById("control").textContent === "control: free", POLL);
  await b.click("#take-control");
  result.secondTakeControlAfterRelease = await answer(b, "take_control", 2);
  await b.evaluate(async () => { await window.rigctlConsole.send("resume"); window.rigctlConsole.disconnect(); });
  await b.close();
  await a.bringToFront();
  await a.waitForFunction(() => document.getElementById("control").textContent === "control: free", POLL);
}

async function commandsScenario(browser, args, result, log) {
  const a = await openConsole(browser, args.url, log);
  // The page's signing against the test vector of docs/operator-commands.md.
  result.testVector = await a.evaluate(async () => {
    const key = Array.from({ length: 32 }, (_, i) => i.toString(16).padStart(2, "0")).join("");
    const c = { version: 1, sender: "alice@rigpc", sequence: 42, utime: 1700000000000000, command: "setpoint", value: 0.01 };
    return { canonical: rigctl.signing.toHex(rigctl.signing.canonicalBytes(c)), tag: await rigctl.signing.sign(key, c) };
  });
  await tracesUpdate(a, result);
  await pauseAndWindow(a, result);
  await setField(a, "#sender", "alice");
  await setField(a, "#key", args.key);
  await a.click("#take-control");
  result.takeControl = await answer(a, "take_control");
  await driveToRunning(a, result);
  // 4 s of running (400 samples a second): the ramp away from home is on the screenshot.
  await a.waitForFunction((n) => Number(document.getElementById("scope-stats").dataset.samples) > n, POLL, (await samples(a)) + 1600);
  await a.screenshot({ path: path.join(args.screenshots, "scope.png") });
  await refusalsAndHold(a, args, result);
  const station = await a.$("#station-panel");
  await station.screenshot({ path: path.join(args.screenshots, "station.png") });
  const b = await secondConsole(browser, args, result, log);
  result.malformed = await malformedClient(args.url.replace(/^http/, "ws"));
  await a.bringToFront();
  result.stateAfterMalformed = await state(a);
  await disconnectMidCommand(a, b, result);
  await a.click("#take-control");
  result.takeControlAgain = await answer(a, "take_control", 2);
  await a.click("h2");
  await a.keyboard.press("s");  // the stop shortcut
  result.stop = await answer(a, "stop");
  await waitState(a, "hydraulics_high");
  result.finalState = await state(a);
}

async function tripScenario(browser, args, result, log) {
  const a = await openConsole(browser, args.url, log);
  await a.waitForSelector("#detectors tr.tripped");
  await a.waitForSelector("#timing tr");  // the loop's timing, published about once a second
  await setField(a, "#sender", "alice");
  await setField(a, "#key", args.key);
  await a.click("#take-control");
  result.takeControl = await answer(a, "take_control");
  await a.click('#command-buttons button[data-command="reset"]');
  result.reset = await answer(a, "reset");
  // The rig refuses the reset while x_r is at its rail: an event with the reason.
  await a.waitForFunction(() => /reset refused/.test(document.getElementById("events").textContent), POLL);
  result.trips = await a.$$eval("#trips li", (items) => items.map((e) => e.textContent));
  result.tripped = await a.$$eval("#detectors tr.tripped td:first-child", (items) => items.map((e) => e.textContent));
  result.events = await a.$$eval("#events li", (items) => items.map((e) => e.textContent));
  result.state = await state(a);
  await a.screenshot({ path: path.join(args.screenshots, "trip.png"), fullPage: true });
}

const procedureTotal = (page) => page.$eval("#procedure-cycles", (e) => Number(e.dataset.total || -1));

async function procedureScenario(browser, args, result, log) {
  const a = await openConsole(browser, args.url, log);
  await setField(a, "#sender", "alice");
  await setField(a, "#key", args.key);
  await a.click("#take-control");
  result.takeControl = await answer(a, "take_control");
  await driveToRunning(a, result);
  // The panel appears with the first RIGCTL_PROCEDURE message and counts.
  await a.waitForFunction(() => !document.getElementById("procedure-panel").hidden &&
                                Number(document.getElementById("procedure-cycles").dataset.total) >= 2, POLL);
  await a.click('#command-buttons button[data-command="hold"]');
  result.hold = await answer(a, "hold");
  await waitState(a, "holding");
  result.cyclesAtHold = await procedureTotal(a);
  await a.click('#command-buttons button[data-command="resume"]');
  result.resume = await answer(a, "resume");
  await waitState(a, "running");
  await a.waitForFunction((n) => Number(document.getElementById("procedure-cycles").dataset.total) > n, POLL, result.cyclesAtHold);
  // Every message the page renders from here: was the request shown?
  await a.evaluate(() => {
    window.sawStopRequest = false;
    const render = rigctl.procedure.render;
    rigctl.procedure.render = (m) => { if (m.stop_at_block_end) window.sawStopRequest = true; render(m); };
  });
  result.cyclesAtRequest = await procedureTotal(a);
  await a.click('#command-buttons button[data-command="stop_at_block_end"]');
  result.stopAtBlockEnd = await answer(a, "stop_at_block_end");
  await waitState(a, "hydraulics_high");
  result.sawStopRequest = await a.evaluate(() => window.sawStopRequest);
  result.requestAfterStop = await a.$eval("#procedure-request", (e) => e.dataset.stopAtBlockEnd);
  // The last messages of the stop reach the page after the state: wait for the count to settle on a pass.
  result.cyclesAtStop = await procedureTotal(a);
  result.panel = await a.$$eval("#procedure tr", (rows) => rows.map((r) => r.textContent.trim().replace(/\s+/g, " ")));
  await (await a.$("#procedure-panel")).screenshot({ path: path.join(args.screenshots, "procedure.png") });
  await a.click('#command-buttons button[data-command="hydraulics_off"]');
  result.hydraulicsOff = await answer(a, "hydraulics_off");
}

async function channelsScenario(browser, args, result, log) {
  const a = await openConsole(browser, args.url, log);
  // Every channel's demand has come and updated: x_ref_2 arrives on its own topic (RIGCTL_CHANNELS).
  await a.waitForFunction(() => {
    const s = window.rigctlConsole.scope.series;
    return ["x_ref_1", "z_r1", "x_ref_2", "z_r2", "u_1", "u_2"].every((n) => s.has(n) && s.get(n).received > 200);
  }, POLL);
  result.toggles = await a.$$eval("#channels input", (items) => items.map((e) => ({ name: e.dataset.channel, checked: e.checked })));
  result.series = await a.evaluate(() => [...window.rigctlConsole.scope.series.values()].map((s) => ({
    name: s.name, group: s.group, unit: s.unit, received: s.received })));
  result.strips = await a.evaluate(() => window.rigctlConsole.scope.strips().map(([unit, list]) => list.map((s) => s.name)));
  const drawn = await a.evaluate(() => window.rigctlConsole.scope.drawn);
  await a.waitForFunction((n) => window.rigctlConsole.scope.drawn > n, POLL, drawn);
  result.framesDrawn = await a.evaluate(() => window.rigctlConsole.scope.drawn);
  await a.screenshot({ path: path.join(args.screenshots, "two_poster.png"), fullPage: true });
}

async function main() {
  const args = parseArgs(process.argv);
  fs.mkdirSync(args.screenshots, { recursive: true });
  const result = { answers: [], log: [] };
  const { browser, userDataDir } = await launch();
  let code = 0;
  try {
    if (args.scenario === "trip") await tripScenario(browser, args, result, result.log);
    else if (args.scenario === "procedure") await procedureScenario(browser, args, result, result.log);
    else if (args.scenario === "channels") await channelsScenario(browser, args, result, result.log);
    else await commandsScenario(browser, args, result, result.log);
  } catch (e) {
    result.error = String(e && e.stack || e);
    code = 1;
  } finally {
    await browser.close();
    fs.rmSync(userDataDir, { recursive: true, force: true });
    fs.writeFileSync(args.out, JSON.stringify(result, null, 2));
  }
  console.log(code === 0 ? "done" : "failed: " + result.error);
  process.exit(code);
}

main();
