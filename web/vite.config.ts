// Vite builds the console into dist/ with relative asset paths, so the server can serve it from
// any prefix. `npm run dev` proxies the API and the event stream to a running `corridor serve`
// (CORRIDOR_URL, default http://127.0.0.1:8080), so the page stays same-origin as in production.
import { defineConfig } from 'vitest/config';

const target = process.env.CORRIDOR_URL ?? 'http://127.0.0.1:8080';

export default defineConfig({
  // Absolute, so a client-side route such as /missions/3 still finds /assets/.
  base: '/',
  build: {
    outDir: 'dist',
    // The module-preload polyfill is the only script Vite would inline; the CSP forbids inline
    // scripts and every browser the console targets supports modulepreload.
    modulePreload: { polyfill: false },
    sourcemap: false,
    chunkSizeWarningLimit: 800,
  },
  server: {
    proxy: {
      '/v1': { target, ws: true, changeOrigin: false },
    },
  },
  test: {
    include: ['test/**/*.test.ts'],
    environment: 'node',
  },
});
