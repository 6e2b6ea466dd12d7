// The console against the real server, through the clicks a dispatcher makes: sign in, dispatch a
// mission on the map, watch the vehicle move, report congestion on its route and see the route
// change, see a signal held green, cancel; a viewer sees no controls; nothing leaves the origin.
// Run: CORRIDOR_BIN=build/app/corridor npm run e2e (see harness.mjs for the other variables).
import assert from 'node:assert/strict';
import { existsSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { after, before, describe, it } from 'node:test';
import {
  DEV_TOKEN,
  SENSOR_TOKEN,
  VIEWER_TOKEN,
  api,
  artifactsDir,
  bearing,
  launchBrowser,
  metres,
  startFront,
  startServer,
  waitFor,
} from './harness.mjs';

const ORIGIN = { lat: 43.7384, lon: 7.4246 };
const DESTINATION = { lat: 43.7496, lon: 7.4365 };

/** Opens the console, signs in with token, waits until the map is drawn and the stream is live. */
async function signIn(browser, base, token) {
  const context = await browser.newContext({ viewport: { width: 1400, height: 900 } });
  const page = await context.newPage();
  const requests = [];
  const problems = [];
  page.on('request', (r) => requests.push(r.url()));
  page.on('websocket', (ws) => requests.push(ws.url()));
  page.on('pageerror', (e) => problems.push(`pageerror: ${e.message}`));
  page.on('console', (m) => {
    if (m.type() === 'error') problems.push(`console: ${m.text()}`);
  });
  await page.goto(base + '/');
  await page.getByTestId('token-input').fill(token);
  await page.getByTestId('token-submit').click();
  await page.locator('[data-testid="map"][data-ready="true"]').waitFor({ timeout: 30_000 });
  await page.locator('[data-testid="connection-status"][data-state="live"]').waitFor({ timeout: 15_000 });
  return { context, page, requests, problems };
}

/** Page coordinates of a lat/lon on the map (the console's read-only test hook). */
async function pagePoint(page, lat, lon) {
  const p = await page.evaluate(([a, b]) => window.__corridor.pagePoint(a, b), [lat, lon]);
  assert.ok(p, 'the map is not ready');
  return p;
}

/** Page coordinates once the map has stopped moving (two reads 250 ms apart agree). */
async function stablePoint(page, lat, lon) {
  let p = await pagePoint(page, lat, lon);
  for (let i = 0; i < 20; i++) {
    await page.waitForTimeout(250);
    const q = await pagePoint(page, lat, lon);
    if (Math.abs(q.x - p.x) < 0.5 && Math.abs(q.y - p.y) < 0.5) return q;
    p = q;
  }
  return p;
}

/** Zooms the map in around a point the way a user does: the mouse wheel over it. */
async function zoomAt(page, lat, lon, notches) {
  // Zoom out around the map's centre until the point is on screen again.
  const box = await page.getByTestId('map').boundingBox();
  const inside = (p) => p.x > box.x + 20 && p.x < box.x + box.width - 20 && p.y > box.y + 20 && p.y < box.y + box.height - 20;
  for (let i = 0; i < 10 && !inside(await stablePoint(page, lat, lon)); i++) {
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.wheel(0, 240);
  }
  for (let i = 0; i < notches; i++) {
    const p = await stablePoint(page, lat, lon);
    await page.mouse.move(p.x, p.y);
    await page.mouse.wheel(0, -240);
  }
  return stablePoint(page, lat, lon);
}

describe('dispatch console (Monaco)', () => {
  let server;
  let front = null;
  let base;
  let browser;
  let artifacts;
  let step = 0;
  let dispatcher;
  let missionId;
  let mission;
  const shot = async (page, name) => {
    step++;
    const file = join(artifacts, `${String(step).padStart(2, '0')}-${name}.png`);
    await page.screenshot({ path: file });
    return file;
  };

  before(async () => {
    artifacts = artifactsDir();
    server = await startServer();
    if (process.env.CORRIDOR_E2E_DIST) {
      front = await startFront(process.env.CORRIDOR_E2E_DIST, server.url);
      base = front.url;
    } else {
      base = server.url;
      const res = await fetch(base + '/');
      const type = res.headers.get('content-type') ?? '';
      assert.ok(res.ok && type.includes('text/html'), `the server does not serve the console at / (${res.status} ${type}); build web/ and set CORRIDOR_E2E_DIST=web/dist to serve it from the test`);
    }
    browser = await launchBrowser();
    console.log(`server ${server.url}, console ${base}, artifacts ${artifacts}`);
  });

  after(async () => {
    await dispatcher?.context.close().catch(() => {});
    await browser?.close().catch(() => {});
    await front?.stop();
    await server?.stop();
  });

  it('signs in with the token and draws the road graph with its attribution', async () => {
    // The vehicle reports where it is first, so the mission can start from its last position.
    await api(server.url, 'POST', '/v1/vehicles/amb-1/position', {
      body: { lat: ORIGIN.lat, lon: ORIGIN.lon, timestamp: Date.now() / 1000, heading_deg: 30, speed_mps: 0, source: 'gps' },
    });
    dispatcher = await signIn(browser, base, DEV_TOKEN);
    const { page } = dispatcher;
    assert.match(await page.getByTestId('attribution').innerText(), /OpenStreetMap/);
    assert.equal(await page.evaluate(() => sessionStorage.getItem('corridor.token')), DEV_TOKEN);
    assert.ok((await page.evaluate(() => window.__corridor.mapFeatures)) > 100);
    await page.getByTestId('vehicle-amb-1').waitFor();
    assert.ok(await page.getByTestId('dispatch-panel').isVisible());
    assert.ok(await page.getByTestId('congestion-panel').isVisible());
    await shot(page, 'signed-in');
  });

  it('creates a mission by clicking the destination and draws its route and preemption schedule', async () => {
    const { page } = dispatcher;
    // A street name from the map's own names puts the destination on that street...
    await page.getByTestId('street-search').fill("Boulevard d'Italie");
    await page.getByTestId('street-go').click();
    await waitFor('the searched street as destination', async () => (await page.getByTestId('destination-text').innerText()).startsWith('43.7'));
    await page.getByTestId('destination-pin').waitFor();
    // ...and a click on the map moves it.
    await page.getByTestId('vehicle-input').fill('amb-1');
    await page.getByTestId('priority-input').fill('3');
    await page.getByTestId('profile-input').selectOption('fire_engine');
    await zoomAt(page, DESTINATION.lat, DESTINATION.lon, 0);
    const p = await stablePoint(page, DESTINATION.lat, DESTINATION.lon);
    await page.mouse.click(p.x, p.y);
    await waitFor('the clicked destination', async () => {
      const [lat, lon] = (await page.getByTestId('destination-text').innerText()).split(',').map(Number);
      return metres([lon, lat], [DESTINATION.lon, DESTINATION.lat]) < 20;
    });
    await page.getByTestId('create-mission').click();
    await page.locator('[data-testid="mission-detail"]:not([hidden])').waitFor();
    assert.equal(await page.getByTestId('dispatch-error').innerText(), '');
    missionId = Number(await page.getByTestId('mission-detail').getAttribute('data-mission'));
    assert.ok(missionId > 0);
    mission = (await api(server.url, 'GET', `/v1/missions/${missionId}`)).json;
    assert.equal(mission.vehicle_id, 'amb-1');
    assert.equal(mission.priority, 3);
    assert.equal(mission.profile, 'fire_engine');
    assert.ok(mission.route, 'the mission has a route');
    assert.ok(mission.preemption.length > 0, 'the route crosses signals');
    await waitFor('the route in the page', () =>
      page.evaluate((id) => window.__corridor.state().missions[id]?.route?.geometry.coordinates.length ?? 0, missionId),
    );
    assert.ok((await page.getByTestId('steps').locator('li').count()) >= 2);
    assert.equal(await page.getByTestId('preemption-schedule').locator('tr').count(), mission.preemption.length);
    await page.locator(`[data-testid="schedule-${missionId}-${mission.preemption[0].signal}"]`).waitFor();
    // The countdown shows the server's predicted arrival (eta_at_s) as time left.
    const eta = await page.getByTestId(`eta-${missionId}`).innerText();
    assert.match(eta, /^\d+:\d\d$/);
    const [mm, ss] = eta.split(':').map(Number);
    const left = mission.eta_at_s - Date.now() / 1000;
    assert.ok(Math.abs(mm * 60 + ss - left) < 5, `countdown ${eta}, server eta_at_s is ${left.toFixed(1)} s away`);
    await page.locator('[data-testid="route-history"] tr[data-testid="revision-1"]').waitFor();
    await shot(page, 'mission-created');
  });

  it('moves the vehicle marker as positions are posted', async () => {
    const { page } = dispatcher;
    const coords = mission.route.geometry.coordinates;
    const marker = page.getByTestId('vehicle-amb-1');
    const before = Number(await marker.getAttribute('data-lat'));
    for (const i of [1, 2, 3]) {
      const c = coords[Math.min(i, coords.length - 1)];
      const next = coords[Math.min(i + 1, coords.length - 1)];
      await api(server.url, 'POST', '/v1/vehicles/amb-1/position', {
        body: { lat: c[1], lon: c[0], timestamp: Date.now() / 1000, heading_deg: bearing(c, next), speed_mps: 8, source: 'gps' },
      });
    }
    const c = coords[Math.min(3, coords.length - 1)];
    await waitFor('the marker at the last position', async () => {
      const lat = Number(await marker.getAttribute('data-lat'));
      const lon = Number(await marker.getAttribute('data-lon'));
      return lat !== before && metres([lon, lat], c) < 30;
    });
    const heading = Number(await marker.getAttribute('data-heading'));
    assert.ok(Number.isFinite(heading));
    const transform = await marker.locator('.vehicle-arrow').evaluate((el) => el.style.transform);
    assert.match(transform, /rotate\(/);
    await shot(page, 'vehicle-moved');
  });

  it('reports congestion on a route edge from the map and shows the route change with reason "congestion"', async () => {
    const { page } = dispatcher;
    const map = (await api(server.url, 'GET', '/v1/map')).json;
    const byEdge = new Map(map.features.map((f) => [f.properties.edge, f]));
    const current = (await api(server.url, 'GET', `/v1/missions/${missionId}`)).json;
    const edges = current.route.properties.edges;
    // Edges ahead of the vehicle, longest first: the easiest to hit and the likeliest to reroute.
    const candidates = edges
      .slice(Math.floor(edges.length / 3), edges.length - 1)
      .map((e) => byEdge.get(e))
      .filter(Boolean)
      .sort((a, b) => b.properties.length_m - a.properties.length_m);
    await page.getByTestId('congestion-mode').click();
    assert.equal(await page.getByTestId('congestion-mode').getAttribute('aria-pressed'), 'true');
    let changed = false;
    for (const f of candidates.slice(0, 4)) {
      const cs = f.geometry.coordinates;
      const k = Math.floor((cs.length - 1) / 2);
      const mid = [(cs[k][0] + cs[k + 1][0]) / 2, (cs[k][1] + cs[k + 1][1]) / 2];
      const p = await zoomAt(page, mid[1], mid[0], 2);
      await page.mouse.click(p.x, p.y);
      const picked = Number(await page.getByTestId('congestion-edge').getAttribute('data-edge'));
      assert.ok([f.properties.edge, f.properties.twin].includes(picked), `clicked edge ${f.properties.edge}, the form picked ${picked}`);
      await page.getByTestId('congestion-factor').fill('50');
      await page.getByTestId('congestion-submit').click();
      await waitFor('the congestion answer', async () => /edge\(s\) changed/.test(await page.getByTestId('congestion-result').innerText()));
      const result = await page.getByTestId('congestion-result').innerText();
      if (/\b[1-9]\d* route\(s\) changed/.test(result)) {
        changed = true;
        break;
      }
    }
    assert.ok(changed, 'a factor of 50 on a route edge changed the route');
    await page.locator('[data-testid="route-history"] tr[data-reason="congestion"]').first().waitFor({ timeout: 10_000 });
    const revisions = (await api(server.url, 'GET', `/v1/missions/${missionId}/routes`)).json.revisions;
    assert.ok(revisions.some((r) => r.reason === 'congestion'));
    // The old route is still drawn, faded, for a while.
    assert.ok(await page.evaluate((id) => Boolean(window.__corridor.state().previousRoutes[id]), missionId));
    await page.getByTestId('congestion-mode').click();
    await shot(page, 'congestion-reroute');
  });

  it('shows a signal held green once the vehicle is close enough for its preemption to start', async () => {
    const { page } = dispatcher;
    const current = (await api(server.url, 'GET', `/v1/missions/${missionId}`)).json;
    const coords = current.route.geometry.coordinates;
    // A signal still ahead on the route: one the reroute left behind is cancelled and never starts.
    const target = current.preemption.find((e) => e.state === 'planned' || e.state === 'active');
    assert.ok(target, `a planned preemption on the route: ${JSON.stringify(current.preemption.map((e) => e.state))}`);
    const at = [target.location.lon, target.location.lat];
    let k = 0;
    coords.forEach((c, i) => {
      if (metres(c, at) < metres(coords[k], at)) k = i;
    });
    // Walk the route towards the signal, a report every ~15 m, until its preemption starts.
    const path = [];
    for (let i = 0; i < k; i++) {
      const n = Math.max(1, Math.round(metres(coords[i], coords[i + 1]) / 15));
      for (let j = 0; j < n; j++) {
        const t = j / n;
        path.push([coords[i][0] + t * (coords[i + 1][0] - coords[i][0]), coords[i][1] + t * (coords[i + 1][1] - coords[i][1]), bearing(coords[i], coords[i + 1])]);
      }
    }
    const start = path.findIndex((p) => metres(p, at) < 150);
    let held = false;
    for (let i = Math.max(0, start); i < path.length && !held; i++) {
      const p = path[i];
      await api(server.url, 'POST', '/v1/vehicles/amb-1/position', {
        body: { lat: p[1], lon: p[0], timestamp: Date.now() / 1000, heading_deg: p[2], speed_mps: 10, source: 'gps' },
      });
      for (let w = 0; w < 4 && !held; w++) {
        await new Promise((r) => setTimeout(r, 400));
        const m = (await api(server.url, 'GET', `/v1/missions/${missionId}`)).json;
        const e = m.preemption.find((x) => x.signal === target.signal);
        const s = (await api(server.url, 'GET', `/v1/signals`)).json.signals.find((x) => x.id === target.signal);
        held = e?.state === 'active' && s?.state === 'held';
      }
    }
    assert.ok(held, `signal ${target.signal}: preemption active and signal held`);
    await page.locator(`[data-testid="signal-${target.signal}"][data-state="held"]`).waitFor({ timeout: 10_000 });
    await page.locator(`[data-testid="preemption-${target.signal}"][data-state="active"]`).waitFor({ timeout: 10_000 });
    await page.locator('[data-testid="event-log"] li[data-type="preemption_started"]').first().waitFor();
    // Bring the signal into view for the screenshot (the map may still be zoomed on the reroute).
    await zoomAt(page, target.location.lat, target.location.lon, 0);
    await shot(page, 'signal-held');
  });

  it('filters the event log by mission', async () => {
    const { page } = dispatcher;
    await page.getByTestId('event-filter').selectOption(String(missionId));
    const missions = await page.locator('[data-testid="event-log"] li').evaluateAll((lis) => lis.map((li) => li.dataset.mission ?? ''));
    assert.ok(missions.length > 0);
    assert.ok(missions.every((m) => m === String(missionId)));
    await page.getByTestId('event-filter').selectOption('');
  });

  it('cancels the mission', async () => {
    const { page } = dispatcher;
    await page.getByTestId(`mission-row-${missionId}`).click();
    await page.getByTestId('cancel-mission').click();
    await page.locator(`[data-testid="mission-row-${missionId}"][data-state="cancelled"]`).waitFor();
    assert.equal((await api(server.url, 'GET', `/v1/missions/${missionId}`)).json.state, 'cancelled');
    assert.ok(await page.getByTestId('cancel-mission').isHidden());
    await shot(page, 'mission-cancelled');
  });

  it('shows the server\'s reason when a vehicle has no known position, and dispatches it from a clicked origin', async () => {
    const { page } = dispatcher;
    const problemsBefore = dispatcher.problems.length;
    await page.getByTestId('vehicle-input').fill('amb-3');
    await zoomAt(page, DESTINATION.lat, DESTINATION.lon, 0);
    const d = await stablePoint(page, DESTINATION.lat, DESTINATION.lon);
    await page.mouse.click(d.x, d.y);
    await page.getByTestId('create-mission').click();
    await waitFor('the refusal', async () => (await page.getByTestId('dispatch-error').innerText()).length > 0);
    const refusal = await page.getByTestId('dispatch-error').innerText();
    assert.match(refusal, /^[a-z_]+: .+/);
    // The browser logs the refused request itself; that one is expected.
    const logged = dispatcher.problems.splice(problemsBefore);
    dispatcher.problems.push(...logged.filter((p) => !/status of 422/.test(p)));
    // "Set origin", then a click on the map puts the origin there.
    await page.getByTestId('set-origin').click();
    const o = await stablePoint(page, ORIGIN.lat, ORIGIN.lon);
    await page.mouse.click(o.x, o.y);
    await page.getByTestId('origin-pin').waitFor();
    const [lat, lon] = (await page.getByTestId('origin-text').innerText()).split(',').map(Number);
    assert.ok(metres([lon, lat], [ORIGIN.lon, ORIGIN.lat]) < 20);
    await page.getByTestId('create-mission').click();
    await waitFor('the mission of amb-3', async () =>
      page.evaluate(() => Object.values(window.__corridor.state().missions).find((m) => m.vehicle_id === 'amb-3' && m.state === 'active')?.id ?? null),
    );
    assert.equal(await page.getByTestId('dispatch-error').innerText(), '');
    const id = await page.evaluate(() => Object.values(window.__corridor.state().missions).find((m) => m.vehicle_id === 'amb-3').id);
    const created = (await api(server.url, 'GET', `/v1/missions/${id}`)).json;
    assert.ok(metres(created.route.geometry.coordinates[0], [ORIGIN.lon, ORIGIN.lat]) < 60, 'the route starts at the clicked origin');
    await shot(page, 'origin-by-click');
    await api(server.url, 'POST', `/v1/missions/${id}/cancel`);
    console.log(`refused without an origin: ${refusal}`);
  });

  it('shows a viewer no dispatch or congestion controls, and a sensor only congestion', async () => {
    const viewer = await signIn(browser, base, VIEWER_TOKEN);
    assert.ok(await viewer.page.getByTestId('dispatch-panel').isHidden());
    assert.ok(await viewer.page.getByTestId('congestion-panel').isHidden());
    await viewer.page.getByTestId(`mission-row-${missionId}`).click();
    assert.ok(await viewer.page.getByTestId('cancel-mission').isHidden());
    assert.match(await viewer.page.getByTestId('whoami').innerText(), /wall/);
    await shot(viewer.page, 'viewer');
    await viewer.page.getByTestId('sign-out').click();
    await viewer.page.getByTestId('token-input').waitFor();
    assert.equal(await viewer.page.evaluate(() => sessionStorage.getItem('corridor.token')), null);
    assert.deepEqual(viewer.problems, []);
    await viewer.context.close();

    const sensor = await signIn(browser, base, SENSOR_TOKEN);
    assert.ok(await sensor.page.getByTestId('dispatch-panel').isHidden());
    assert.ok(await sensor.page.getByTestId('congestion-panel').isVisible());
    await sensor.context.close();
  });

  it('reconnects by itself after the server restarts, resynchronises, and follows the new stream', async () => {
    const { page } = dispatcher;
    const eventsBefore = await page.evaluate(() => window.__corridor.state().stats.applied);
    const problemsBefore = dispatcher.problems.length;
    await server.restart();
    await page.locator('[data-testid="connection-status"][data-state="reconnecting"]').waitFor({ timeout: 10_000 });
    assert.match(await page.getByTestId('connection-status').innerText(), /^reconnecting in \d+s$/);
    await shot(page, 'reconnecting');
    // Written while the console is still waiting to reconnect: it must arrive by the resync.
    await api(server.url, 'POST', '/v1/vehicles/amb-2/position', { body: { lat: ORIGIN.lat, lon: ORIGIN.lon, timestamp: Date.now() / 1000, heading_deg: 90 } });
    const created = (await api(server.url, 'POST', '/v1/missions', { body: { vehicle_id: 'amb-2', destination: DESTINATION, priority: 5 } })).json;
    await page.locator('[data-testid="connection-status"][data-state="live"]').waitFor({ timeout: 30_000 });
    await page.getByTestId(`mission-row-${created.id}`).waitFor();
    // The restarted server numbers its events from the start again; the console still applies them.
    const coords = created.route.geometry.coordinates;
    const c = coords[Math.min(2, coords.length - 1)];
    // A minute later, so the move is one a vehicle can drive: the server's tracker does not follow
    // a jump faster than that (it is stored as an outlier).
    await api(server.url, 'POST', '/v1/vehicles/amb-2/position', { body: { lat: c[1], lon: c[0], timestamp: Date.now() / 1000 + 60, heading_deg: 45, speed_mps: 8 } });
    await waitFor('the position after the restart', async () => {
      const lat = Number(await page.getByTestId('vehicle-amb-2').getAttribute('data-lat'));
      return Math.abs(lat - c[1]) < 3e-4;
    });
    assert.ok((await page.evaluate(() => window.__corridor.state().stats.applied)) > eventsBefore);
    await api(server.url, 'POST', `/v1/missions/${created.id}/cancel`);
    await shot(page, 'reconnected');
    // While the server was down the browser logged the refused connections; nothing else counts.
    const during = dispatcher.problems.splice(problemsBefore);
    dispatcher.problems.push(...during.filter((p) => !/Failed to load resource|WebSocket connection to .* failed|ERR_CONNECTION_REFUSED/.test(p)));
  });

  it('made no request to any origin but the server, never put the token in the stream URL, and broke no CSP rule', async () => {
    const origin = new URL(base);
    const foreign = dispatcher.requests.filter((u) => {
      if (u.startsWith('data:') || u.startsWith('blob:')) return false;
      const url = new URL(u);
      return url.host !== origin.host;
    });
    assert.deepEqual(foreign, []);
    const streams = dispatcher.requests.filter((u) => u.startsWith('ws'));
    assert.ok(streams.length >= 1);
    for (const u of streams) {
      assert.match(u, /\/v1\/stream\?ticket=[0-9a-f]{32}$/);
      assert.ok(!u.includes(DEV_TOKEN));
    }
    assert.deepEqual(dispatcher.problems, []);
    writeFileSync(join(artifacts, 'requests.json'), JSON.stringify([...new Set(dispatcher.requests)], null, 2));
  });
});

const PORTO = process.env.CORRIDOR_PORTO_MAP;
describe('dispatch console under load (Porto)', { skip: !PORTO || !existsSync(PORTO) ? 'CORRIDOR_PORTO_MAP is unset or missing' : false }, () => {
  it('draws the map and keeps up with 50 missions and 200 vehicles', { timeout: 900_000 }, async () => {
    const artifacts = artifactsDir();
    const server = await startServer({ map: PORTO, timeoutMs: 600_000 });
    const front = process.env.CORRIDOR_E2E_DIST ? await startFront(process.env.CORRIDOR_E2E_DIST, server.url) : null;
    const base = front?.url ?? server.url;
    const browser = await launchBrowser();
    try {
      const map = (await api(server.url, 'GET', '/v1/map')).json;
      const roads = map.features.filter((f) => ['primary', 'secondary', 'tertiary', 'residential', 'unclassified'].includes(f.properties.class));
      // A fixed pseudo-random sequence, so runs are comparable.
      let seed = 17;
      const rand = () => ((seed = (seed * 1103515245 + 12345) % 2 ** 31) / 2 ** 31);
      const pick = () => roads[Math.floor(rand() * roads.length)].geometry.coordinates[0];
      const vehicles = Array.from({ length: 200 }, (_, i) => ({ id: `v${String(i).padStart(3, '0')}`, at: pick(), route: null, k: 0 }));
      const now = () => Date.now() / 1000;
      await Promise.all(vehicles.map((v) => api(server.url, 'POST', `/v1/vehicles/${v.id}/position`, { body: { lat: v.at[1], lon: v.at[0], timestamp: now(), source: 'gps' } })));
      let created = 0;
      for (const v of vehicles) {
        if (created >= 50) break;
        for (let tries = 0; tries < 5; tries++) {
          const d = pick();
          const r = await api(server.url, 'POST', '/v1/missions', { body: { vehicle_id: v.id, destination: { lat: d[1], lon: d[0] }, priority: 1 + (created % 10) }, allow: [422] });
          if (r.status === 201) {
            v.route = r.json.route.geometry.coordinates;
            created++;
            break;
          }
        }
      }
      assert.equal(created, 50);

      const t0 = Date.now();
      const session = await signIn(browser, base, DEV_TOKEN);
      const signInToLiveMs = Date.now() - t0;
      const mapReadyMs = await session.page.evaluate(() => window.__corridor.mapReadyMs);
      const features = await session.page.evaluate(() => window.__corridor.mapFeatures);
      await session.page.evaluate(() => window.__corridor.fps.start());
      // ~5 s of live updates: every vehicle reports twice a second (missions along their routes).
      let posted = 0;
      const until = Date.now() + 5000;
      while (Date.now() < until) {
        const tick = Date.now();
        await Promise.all(
          vehicles.map((v) => {
            let c;
            if (v.route) {
              v.k = Math.min(v.k + 1, v.route.length - 1);
              c = v.route[v.k];
            } else {
              c = [v.at[0] + (rand() - 0.5) * 1e-4, v.at[1] + (rand() - 0.5) * 1e-4];
            }
            posted++;
            return api(server.url, 'POST', `/v1/vehicles/${v.id}/position`, { body: { lat: c[1], lon: c[0], timestamp: now(), heading_deg: rand() * 360, speed_mps: 10, source: 'gps' }, allow: [409, 422] });
          }),
        );
        await new Promise((r) => setTimeout(r, Math.max(0, 500 - (Date.now() - tick))));
      }
      const fps = await session.page.evaluate(() => window.__corridor.fps.stop());
      const state = await session.page.evaluate(() => {
        const s = window.__corridor.state();
        return { missions: Object.values(s.missions).filter((m) => m.state === 'active').length, vehicles: Object.keys(s.vehicles).length, events: s.stats.applied };
      });
      await session.page.screenshot({ path: join(artifacts, 'porto-load.png') });
      const result = { map: PORTO, map_features: features, map_ready_ms: Math.round(mapReadyMs), sign_in_to_live_ms: signInToLiveMs, positions_posted: posted, ...fps, page: state };
      writeFileSync(join(artifacts, 'porto_perf.json'), JSON.stringify(result, null, 2));
      console.log(`porto ${JSON.stringify(result)}`);
      assert.equal(state.missions, 50);
      assert.equal(state.vehicles, 200);
      await session.context.close();
    } finally {
      await browser.close();
      await front?.stop();
      await server.stop();
    }
  });
});
