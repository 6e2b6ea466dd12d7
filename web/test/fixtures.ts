// Missions, events and snapshots for the store tests, shaped like the server's answers.
import type { Mission, ScheduleEntry, ServerEvent, Signal, Vehicle } from '../src/api/types';

export const T0 = 1_700_000_000;

export function route(coordinates: number[][], factors?: (number | null)[], index?: number[]): NonNullable<Mission['route']> {
  return {
    type: 'Feature',
    geometry: { type: 'LineString', coordinates },
    properties: {
      travel_time_s: 120,
      length_m: 1000,
      algorithm: 'dstar',
      nodes: [],
      edges: [],
      osm_nodes: [],
      arrival_s: [],
      signals: [408],
      ...(index ? { edge_coordinate_index: index } : {}),
      ...(factors ? { congestion_factors: factors } : {}),
      steps: [],
    },
  };
}

export function entry(signal: number, state = 'planned'): ScheduleEntry {
  return {
    signal,
    osm_node: 21915639,
    location: { lat: 43.7404, lon: 7.4256 },
    movement: 'S->N',
    phase: '4+8',
    congestion: 'low',
    start_s: T0 + 30,
    arrival_s: T0 + 38,
    release_s: T0 + 46,
    state,
    deferred: false,
  };
}

export function mission(id: number, over: Partial<Mission> = {}): Mission {
  return {
    id,
    vehicle_id: `amb-${id}`,
    state: 'active',
    priority: 2,
    vmax_kmh: 120,
    profile: 'ambulance',
    destination: { lat: 43.7496, lon: 7.4365 },
    route_revision: 1,
    created_s: T0,
    updated_s: T0,
    last_position: { lat: 43.7384, lon: 7.4246 },
    eta_s: 120,
    eta_at_s: T0 + 120,
    preemption: [entry(408), entry(112)],
    route: route([
      [7.4246, 43.7384],
      [7.4256, 43.7404],
      [7.4365, 43.7496],
    ]),
    ...over,
  };
}

export function vehicle(id: string, over: Partial<Vehicle> = {}): Vehicle {
  return { vehicle_id: id, lat: 43.7384, lon: 7.4246, heading_deg: 30, speed_mps: 10, timestamp: T0, source: 'gps', mission: null, ...over };
}

export function signal(id: number, state: Signal['state'] = 'normal'): Signal {
  return { id, osm_node: 1000 + id, location: { lat: 43.74, lon: 7.42 }, phases: ['2+6', '4+8'], lights: [], mode: 'program', program_step: 0, state };
}

/** Events numbered from seq, one second apart from T0 + seq. */
export function ev(seq: number, type: string, fields: Partial<ServerEvent> = {}): ServerEvent {
  return { seq, type, mission: null, reason: '', time_s: T0 + seq, ...fields };
}

export function position(seq: number, missionId: number, lat: number, lon: number, eta: number | null = null): ServerEvent {
  return ev(seq, 'position', { mission: missionId, vehicle_id: `amb-${missionId}`, lat, lon, heading_deg: 45, speed_mps: 12, eta_s: eta, source: 'gps' });
}
