// The console's entry: sign in, load the road graph, start the stream, and render the store into
// the map layers and panels once per animation frame.
import 'leaflet/dist/leaflet.css';
import './styles.css';
import L from 'leaflet';
import { ApiClient, ApiError, streamUrl } from './api/client';
import type { Me } from './api/types';
import { createBaseMap, escapeHtml, type BaseMap } from './map/basemap';
import { RouteLayers } from './map/routes';
import { SignalLayer } from './map/signals';
import { VehicleLayer } from './map/vehicles';
import { CongestionPanel } from './panels/congestion';
import { DispatchPanel, type ClickMode } from './panels/dispatch';
import { byTestId } from './panels/dom';
import { EventLog } from './panels/eventlog';
import { forgetToken, hideLogin, showLogin, storedToken } from './panels/login';
import { MissionPanel } from './panels/missions';
import { renderStatus } from './panels/status';
import type { State } from './store/state';
import { Store } from './store/store';
import { Sync } from './store/sync';

/** What the end-to-end tests may read: timings, the state, and a frame counter. */
interface TestHook {
  mapReadyMs: number | null;
  mapFeatures: number;
  state: () => State;
  /** Page coordinates (CSS pixels) of a lat/lon on the map, for clicking it. */
  pagePoint: (lat: number, lon: number) => { x: number; y: number } | null;
  fps: {
    start: () => void;
    stop: () => { frames: number; renders: number; seconds: number; fps: number; renders_per_s: number; render_ms_mean: number; render_ms_max: number };
  };
}

declare global {
  interface Window {
    __corridor: TestHook;
  }
}

const store = new Store((fn) => requestAnimationFrame(fn));
const api = new ApiClient('');
let map: L.Map | null = null;
let renders = 0;
/** Time spent in render (ms): total and longest since the frame counter started. */
const renderTime = { total: 0, max: 0 };

const timings = { mapReadyMs: null as number | null, mapFeatures: 0 };
let frames = 0;
let framesFrom = 0;
let rendersFrom = 0;
let counting = false;
const countFrames = () => {
  if (!counting) return;
  frames++;
  requestAnimationFrame(countFrames);
};
const hook: TestHook = Object.freeze({
  get mapReadyMs() {
    return timings.mapReadyMs;
  },
  get mapFeatures() {
    return timings.mapFeatures;
  },
  state: () => store.getState(),
  pagePoint: (lat: number, lon: number) => {
    if (!map) return null;
    const p = map.latLngToContainerPoint([lat, lon]);
    const r = map.getContainer().getBoundingClientRect();
    return { x: r.left + p.x, y: r.top + p.y };
  },
  fps: Object.freeze({
    start: () => {
      frames = 0;
      rendersFrom = renders;
      renderTime.total = 0;
      renderTime.max = 0;
      framesFrom = performance.now();
      counting = true;
      requestAnimationFrame(countFrames);
    },
    stop: () => {
      counting = false;
      const seconds = (performance.now() - framesFrom) / 1000;
      const r = renders - rendersFrom;
      return {
        frames,
        renders: r,
        seconds,
        fps: frames / seconds,
        renders_per_s: r / seconds,
        render_ms_mean: r > 0 ? renderTime.total / r : 0,
        render_ms_max: renderTime.max,
      };
    },
  }),
});
window.__corridor = hook;

function signOut(): void {
  forgetToken();
  location.reload();
}

async function signIn(token: string): Promise<void> {
  api.setToken(token);
  let me: Me;
  try {
    me = await api.me();
  } catch (e) {
    forgetToken();
    const why = e instanceof ApiError && (e.status === 401 || e.status === 403) ? 'The server refused this token.' : `Cannot sign in: ${(e as Error).message}`;
    showLogin(why, (t) => void signIn(t));
    return;
  }
  store.dispatch({ type: 'me', me });
  hideLogin();
  byTestId('whoami').textContent = `${me.name} (${me.roles.join(', ')})`;
  byTestId('sign-out').onclick = signOut;
  await start(me);
}

async function start(me: Me): Promise<void> {
  const t0 = performance.now();
  map = L.map('map', { preferCanvas: true, zoomSnap: 0.25, zoomControl: true, attributionControl: true, minZoom: 3, maxZoom: 19 });
  map.attributionControl.setPrefix('<a href="https://leafletjs.com">Leaflet</a>');
  const fc = await api.map().catch((e: Error) => {
    byTestId('connection-status').textContent = `map: ${e.message}`;
    throw e;
  });
  const [[minLon, minLat], [maxLon, maxLat]] = fc.bounds ?? [[-180, -85], [180, 85]];
  map.fitBounds([
    [minLat, minLon],
    [maxLat, maxLon],
  ]);
  const base: BaseMap = createBaseMap(map, fc);
  map.attributionControl.addAttribution(escapeHtml(base.attribution));
  map.attributionControl.getContainer()?.setAttribute('data-testid', 'attribution');
  timings.mapFeatures = fc.features.length;
  addLegend(map);
  requestAnimationFrame(() => {
    timings.mapReadyMs = performance.now() - t0;
    byTestId('map').dataset.ready = 'true';
  });

  const signals = new SignalLayer(map);
  const routes = new RouteLayers(map);
  const vehicles = new VehicleLayer(map);
  const sync = new Sync({
    api,
    store,
    openSocket: (url) => new WebSocket(url),
    streamUrl: (ticket) => streamUrl(location, ticket),
    isOnline: () => navigator.onLine,
    // The map and panels exist already: with the new token (saved by the form) start afresh.
    onAuthFailure: () => showLogin('The server refused the token; sign in again.', () => location.reload()),
  });
  const select = (id: number) => {
    store.dispatch({ type: 'select', mission: id });
    void sync.refreshRoutes(id);
    void sync.refreshMission(id);
    void sync.refreshCalls(id);
  };
  vehicles.onClick((v) => {
    if (v.mission !== null && v.mission !== undefined) select(v.mission);
  });

  const roles = new Set(me.roles);
  const mode: ClickMode = { current: 'destination' };
  const dispatch = roles.has('dispatcher') ? new DispatchPanel(map, api, store, sync, mode, base) : null;
  const congestion = roles.has('sensor')
    ? new CongestionPanel(api, mode, (m) => {
        if (dispatch) dispatch.setMode(m);
        else mode.current = m;
        map?.getContainer().classList.toggle('picking', m === 'congestion');
      }, base)
    : null;
  const missions = new MissionPanel(store, api, roles.has('dispatcher'), select);
  const log = new EventLog(() => store.getState());

  // The map shows a newly selected mission's whole route once (after a click in the list, on its
  // vehicle, or when the dispatcher has just created it); afterwards the view is the user's.
  let fitted: number | null = null;
  const render = (state: State, previous: State | null) => {
    renders++;
    const t = performance.now();
    const now = Date.now();
    renderStatus(state, now);
    signals.update(state, previous);
    routes.update(state, previous);
    if (state.selectedMission !== fitted) {
      const bounds = state.selectedMission !== null ? routes.bounds(state.selectedMission) : null;
      if (bounds) map?.fitBounds(bounds, { padding: [40, 40], maxZoom: 17, animate: false });
      if (bounds || state.selectedMission === null) fitted = state.selectedMission;
    }
    vehicles.update(state, previous);
    missions.render(state, previous, now);
    log.render(state, previous);
    dispatch?.render(state, previous);
    congestion?.sync();
    const ms = performance.now() - t;
    renderTime.total += ms;
    renderTime.max = Math.max(renderTime.max, ms);
  };
  store.subscribe(render);
  render(store.getState(), null);

  setInterval(() => {
    const now = Date.now();
    const state = store.getState();
    missions.tick(state, now);
    renderStatus(state, now);
    store.dispatch({ type: 'expire', nowMs: now });
  }, 1000);
  window.addEventListener('online', () => sync.reconnectNow());

  sync.start();
  void sync.loadRecent().catch(() => {});
}

function addLegend(m: L.Map): void {
  const legend = new L.Control({ position: 'bottomleft' });
  legend.onAdd = () => {
    const div = L.DomUtil.create('div', 'legend');
    div.setAttribute('data-testid', 'legend');
    L.DomUtil.create('strong', '', div).textContent = 'Route';
    for (const [cls, text] of [
      ['free', 'free flow'],
      ['slow', 'slow (≤2×)'],
      ['heavy', 'heavy'],
      ['closed', 'closed'],
    ] as const) {
      const row = L.DomUtil.create('div', '', div);
      L.DomUtil.create('i', cls, row);
      row.append(text);
    }
    return div;
  };
  legend.addTo(m);
}

const token = storedToken();
if (token) void signIn(token);
else showLogin('', (t) => void signIn(t));
