// Headless Chromium driven over the DevTools protocol on a pipe
// (--remote-debugging-pipe: requests on fd 3, replies on fd 4, each a JSON
// message ended by a NUL byte). The test waits, in real time, for what the page
// says it has done. It used to dump the DOM when a virtual-time budget ran
// out (--virtual-time-budget), and virtual time can move on while the page
// waits for anything but a network fetch (the glTF's PNG is decoded off the
// main thread): on CI's loaded 2-core machine a page was once dumped before it
// had written anything (test_browser, stop 28; not reproduced here in 25 runs
// under load). Waiting for the page's own signal leaves no such race.
import { spawn } from 'node:child_process';
import { existsSync } from 'node:fs';

// ANGLE draws WebGL through whatever Vulkan driver the loader finds: the one
// VK_DRIVER_FILES names, else Chromium's own SwiftShader. The tests pin Mesa's
// lavapipe, the project's reference software device, where the caller names no
// driver. Chromium 156's SwiftShader (Subzero) shades ~10 % of the demo floor's
// pixels, in blocks (its triangles reach behind the camera; whether that is
// the cause was not checked), at a world position 2 cm to 20 cm from the one
// its depth gives (the page's
// position check, viewer.js), up to 43 % off; lavapipe and the C renderer
// agree there to 1e-3.
// PB_BROWSER_VULKAN=bundled leaves Chromium its own driver.
const LAVAPIPE_ICD = ['/usr/share/vulkan/icd.d/lvp_icd.json', '/usr/share/vulkan/icd.d/lvp_icd.x86_64.json'];
function browserEnv() {
    const env = { ...process.env };
    if (env.PB_BROWSER_VULKAN === 'bundled' || env.VK_DRIVER_FILES || env.VK_ICD_FILENAMES) return env;
    const icd = LAVAPIPE_ICD.find((f) => existsSync(f));
    if (icd) env.VK_DRIVER_FILES = env.VK_ICD_FILENAMES = icd;
    return env;
}

const LAUNCH = ['--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--ignore-gpu-blocklist', '--hide-scrollbars', '--no-first-run', '--remote-debugging-pipe'];

// options.commandTimeoutMs: how long one DevTools command may wait for its reply
export async function launch(chromium, width, height, options = {}) {
    const COMMAND_TIMEOUT_MS = options.commandTimeoutMs || 60000;
    const proc = spawn(chromium, [...LAUNCH, `--window-size=${width},${height}`, 'about:blank'],
        { stdio: ['ignore', 'ignore', 'pipe', 'pipe', 'pipe'], env: browserEnv() });
    let stderr = '', pending = Buffer.alloc(0), nextId = 1, exited = null;
    const waiting = new Map();
    proc.stderr.on('data', (d) => { stderr = (stderr + d).slice(-4000); });
    const fail = (why) => {
        exited = why;
        for (const { reject, timer } of waiting.values()) {
            clearTimeout(timer);
            reject(new Error(`${why}; chromium said: ${stderr.slice(-1500)}`));
        }
        waiting.clear();
    };
    proc.on('error', (e) => fail(`${chromium}: ${e.message}`));
    proc.on('exit', (code, signal) => fail(`${chromium} exited (${signal || code})`));
    proc.stdio[4].on('data', (d) => {
        pending = Buffer.concat([pending, d]);
        for (let end; (end = pending.indexOf(0)) >= 0; pending = pending.subarray(end + 1)) {
            const m = JSON.parse(pending.subarray(0, end).toString('utf8'));
            const w = m.id !== undefined && waiting.get(m.id);
            if (!w) continue; // events: not used
            waiting.delete(m.id);
            clearTimeout(w.timer);
            if (m.error) w.reject(new Error(`${w.method}: ${m.error.message}`));
            else w.resolve(m.result);
        }
    });
    // a Chromium that stays alive but stops answering fails the command after
    // COMMAND_TIMEOUT_MS, not the whole test at ctest's limit
    const send = (method, params = {}, sessionId) => new Promise((resolve, reject) => {
        if (exited) { reject(new Error(exited)); return; }
        const id = nextId++;
        const timer = setTimeout(() => {
            waiting.delete(id);
            reject(new Error(`${method}: no reply from ${chromium} in ${COMMAND_TIMEOUT_MS} ms; it said: ${stderr.slice(-1500)}`));
        }, COMMAND_TIMEOUT_MS);
        waiting.set(id, { resolve, reject, method, timer });
        proc.stdio[3].write(JSON.stringify({ id, method, params, ...(sessionId ? { sessionId } : {}) }) + '\0');
    });

    const { targetId } = await send('Target.createTarget', { url: 'about:blank' });
    const { sessionId } = await send('Target.attachToTarget', { targetId, flatten: true });
    const page = (method, params) => send(method, params, sessionId);
    await page('Page.enable');
    // the viewport itself (the new headless mode's window keeps room for
    // browser chrome it does not draw)
    await page('Emulation.setDeviceMetricsOverride', { width, height, deviceScaleFactor: 1, mobile: false });

    // a promise EXPRESSION is awaited
    const evaluate = async (expression) => {
        const r = await page('Runtime.evaluate', { expression, returnByValue: true, awaitPromise: true });
        if (r.exceptionDetails) throw new Error(`${expression}: ${r.exceptionDetails.text}`);
        return r.result.value;
    };
    return {
        pid: proc.pid,
        async goto(url) { await page('Page.navigate', { url }); },
        evaluate,
        // polls EXPRESSION until it gives a truthy value, or fails after
        // timeoutMs of real time naming what it waited for
        async waitFor(expression, timeoutMs) {
            const start = Date.now();
            for (;;) {
                const v = await evaluate(expression).catch(() => undefined); // the page may be between documents
                if (v) return v;
                if (Date.now() - start > timeoutMs)
                    throw new Error(`waited ${timeoutMs} ms for ${expression}; chromium said: ${stderr.slice(-1500)}`);
                await new Promise((ok) => setTimeout(ok, 100));
            }
        },
        async screenshot() {
            const { data } = await page('Page.captureScreenshot', { format: 'png' });
            return Buffer.from(data, 'base64');
        },
        async close() {
            if (exited) return;
            const gone = new Promise((ok) => proc.once('exit', ok));
            await send('Browser.close').catch(() => {});
            const timer = setTimeout(() => proc.kill('SIGKILL'), 5000);
            await gone;
            clearTimeout(timer);
        },
    };
}
