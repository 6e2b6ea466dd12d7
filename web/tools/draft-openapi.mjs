// Writes src/api/openapi.json: a draft OpenAPI 3.0.3 document for the console's types, built from
// the server's component schemas (../server/openapi_schemas.json) and the paths of the API
// contract. Once the server serves its own document, `corridor openapi > src/api/openapi.json`
// replaces this draft and the script is no longer needed.
import { readFileSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const schemas = JSON.parse(readFileSync(join(here, '../../server/openapi_schemas.json'), 'utf8'));

const ref = (name) => ({ $ref: `#/components/schemas/${name}` });
const json = (schema, description = 'OK') => ({ description, content: { 'application/json': { schema } } });
const errors = {
  400: json(ref('Error'), 'Malformed request'),
  401: json(ref('Error'), 'Missing or invalid token'),
  403: json(ref('Error'), 'Token lacks the role'),
  404: json(ref('Error'), 'Unknown id'),
  409: json(ref('Error'), 'State conflict'),
  413: json(ref('Error'), 'Body too large'),
  422: json(ref('Error'), 'Valid JSON that cannot be applied'),
  429: json(ref('Error'), 'Rate limited'),
  503: json(ref('Error'), 'Storage unavailable'),
};
const list = (key, item) => ({ type: 'object', required: [key], properties: { [key]: { type: 'array', items: ref(item) } } });
const idParam = { name: 'id', in: 'path', required: true, schema: { type: 'string' } };
const body = (schema) => ({ required: true, content: { 'application/json': { schema } } });
const secured = { security: [{ bearer: [] }] };
const op = (summary, ok, extra = {}, status = 200) => ({ summary, ...secured, ...extra, responses: { [status]: ok, ...errors } });

const paths = {
  '/v1/health': { get: { summary: 'Liveness, map size and active missions', responses: { 200: json(ref('Health')) } } },
  '/v1/me': { get: op('The caller: name, roles and vehicle', json(ref('Me'))) },
  '/v1/stream/ticket': { post: op('A single-use ticket for the event stream', json(ref('Ticket'))) },
  '/v1/stream': {
    get: {
      summary: 'WebSocket stream of events (upgrade); ?ticket=T, optional ?mission=ID. Each message is one Event.',
      parameters: [
        { name: 'ticket', in: 'query', required: true, schema: { type: 'string' } },
        { name: 'mission', in: 'query', required: false, schema: { type: 'integer' } },
      ],
      responses: { 101: { description: 'Switching protocols' }, 401: json(ref('Error'), 'Bad or expired ticket') },
    },
  },
  '/v1/map': { get: op('The road graph as GeoJSON', json(ref('MapFeatureCollection'))) },
  '/v1/missions': {
    get: op('List missions', json(list('missions', 'Mission')), {
      parameters: [{ name: 'state', in: 'query', required: false, schema: { type: 'string', enum: ['active', 'completed', 'cancelled'] } }],
    }),
    post: op('Create a mission', json(ref('Mission'), 'Created'), { requestBody: body(ref('MissionRequest')) }, 201),
  },
  '/v1/missions/{id}': { get: op('One mission', json(ref('Mission')), { parameters: [idParam] }) },
  '/v1/missions/{id}/cancel': { post: op('Cancel a mission', json(ref('Mission')), { parameters: [idParam] }) },
  '/v1/missions/{id}/routes': {
    get: op('Route history, oldest first', json(list('revisions', 'RouteRevision')), { parameters: [idParam] }),
  },
  '/v1/vehicles': { get: op('Every vehicle with its last position', json(list('vehicles', 'Vehicle'))) },
  '/v1/vehicles/{id}/position': {
    post: op('Report a vehicle position', json(ref('PositionResult')), { parameters: [idParam], requestBody: body(ref('PositionReport')) }),
  },
  '/v1/congestion': {
    post: op('Report congestion on edges or OSM ways', json(ref('CongestionResult')), { requestBody: body(ref('CongestionRequest')) }),
  },
  '/v1/signals': { get: op('Every signalized intersection', json(list('signals', 'Signal'))) },
  '/v1/signals/{id}': { get: op('One signalized intersection', json(ref('Signal')), { parameters: [idParam] }) },
};

const doc = {
  openapi: '3.0.3',
  info: { title: 'Corridor dispatch API (draft for the console)', version: '1' },
  paths,
  components: { securitySchemes: { bearer: { type: 'http', scheme: 'bearer' } }, schemas },
};
writeFileSync(join(here, '../src/api/openapi.json'), JSON.stringify(doc, null, 2) + '\n');
