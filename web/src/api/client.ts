// The typed REST client: one method per endpoint the console uses, bearer token on each request,
// every non-2xx answer turned into an ApiError carrying the server's {code, message}.
import type {
  CongestionRequest,
  CongestionResult,
  MapFeatureCollection,
  Me,
  Mission,
  MissionRequest,
  MissionState,
  PositionReport,
  PositionResult,
  RouteRevision,
  Signal,
  SignalCall,
  Ticket,
  Vehicle,
} from './types';

export class ApiError extends Error {
  constructor(
    readonly status: number,
    readonly code: string,
    message: string,
  ) {
    super(message);
    this.name = 'ApiError';
  }
}

export type FetchLike = (input: string, init?: RequestInit) => Promise<Response>;

export class ApiClient {
  /** base is '' in the browser (same origin); tests pass a fake fetch. */
  constructor(
    private token: string,
    private readonly fetchImpl: FetchLike = (input, init) => fetch(input, init),
    private readonly base = '',
  ) {}

  setToken(token: string): void {
    this.token = token;
  }

  private async request<T>(method: 'GET' | 'POST', path: string, body?: unknown): Promise<T> {
    const headers: Record<string, string> = { Accept: 'application/json' };
    if (this.token) headers.Authorization = `Bearer ${this.token}`;
    if (body !== undefined) headers['Content-Type'] = 'application/json';
    let response: Response;
    try {
      response = await this.fetchImpl(this.base + path, {
        method,
        headers,
        body: body === undefined ? undefined : JSON.stringify(body),
        cache: 'no-store',
      });
    } catch (e) {
      throw new ApiError(0, 'network', `cannot reach the server: ${(e as Error).message}`);
    }
    const text = await response.text();
    let parsed: unknown = null;
    if (text) {
      try {
        parsed = JSON.parse(text);
      } catch {
        if (response.ok) throw new ApiError(response.status, 'bad_response', `${method} ${path}: answer is not JSON`);
      }
    }
    if (!response.ok) {
      const err = (parsed as { error?: { code?: string; message?: string } } | null)?.error;
      throw new ApiError(response.status, err?.code ?? `http_${response.status}`, err?.message ?? `${method} ${path}: HTTP ${response.status}`);
    }
    return parsed as T;
  }

  me(): Promise<Me> {
    return this.request('GET', '/v1/me');
  }
  ticket(): Promise<Ticket> {
    return this.request('POST', '/v1/stream/ticket');
  }
  map(): Promise<MapFeatureCollection> {
    return this.request('GET', '/v1/map');
  }
  async missions(state?: MissionState): Promise<Mission[]> {
    const q = state ? `?state=${state}` : '';
    return (await this.request<{ missions: Mission[] }>('GET', `/v1/missions${q}`)).missions;
  }
  mission(id: number): Promise<Mission> {
    return this.request('GET', `/v1/missions/${id}`);
  }
  createMission(body: MissionRequest): Promise<Mission> {
    return this.request('POST', '/v1/missions', body);
  }
  cancelMission(id: number): Promise<Mission> {
    return this.request('POST', `/v1/missions/${id}/cancel`);
  }
  async routes(id: number): Promise<RouteRevision[]> {
    return (await this.request<{ revisions: RouteRevision[] }>('GET', `/v1/missions/${id}/routes`)).revisions;
  }
  async vehicles(): Promise<Vehicle[]> {
    return (await this.request<{ vehicles: Vehicle[] }>('GET', '/v1/vehicles')).vehicles;
  }
  postPosition(vehicleId: string, report: PositionReport): Promise<PositionResult> {
    return this.request('POST', `/v1/vehicles/${encodeURIComponent(vehicleId)}/position`, report);
  }
  congestion(body: CongestionRequest): Promise<CongestionResult> {
    return this.request('POST', '/v1/congestion', body);
  }
  async signals(): Promise<Signal[]> {
    return (await this.request<{ signals: Signal[] }>('GET', '/v1/signals')).signals;
  }
  /** The call records of a mission's signals on field controllers, newest first. */
  async missionCalls(id: number): Promise<SignalCall[]> {
    return (await this.request<{ calls: SignalCall[] }>('GET', `/v1/missions/${id}/calls`)).calls;
  }
  /** The same records as the server's CSV export (a link cannot carry the bearer token). */
  async missionCallsCsv(id: number): Promise<string> {
    const headers: Record<string, string> = { Accept: 'text/csv' };
    if (this.token) headers.Authorization = `Bearer ${this.token}`;
    let response: Response;
    try {
      response = await this.fetchImpl(`${this.base}/v1/missions/${id}/calls?format=csv`, { method: 'GET', headers, cache: 'no-store' });
    } catch (e) {
      throw new ApiError(0, 'network', `cannot reach the server: ${(e as Error).message}`);
    }
    const text = await response.text();
    if (!response.ok) throw new ApiError(response.status, `http_${response.status}`, `GET calls CSV: HTTP ${response.status}`);
    return text;
  }
}

/** The stream URL on the page's own host: ws: for http:, wss: for https:. */
export function streamUrl(location: { protocol: string; host: string }, ticket: string): string {
  const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
  return `${scheme}//${location.host}/v1/stream?ticket=${encodeURIComponent(ticket)}`;
}
