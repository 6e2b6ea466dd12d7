#!/usr/bin/env bash
# The console's API types are generated from web/src/api/openapi.json; its schemas must be the
# ones the server itself serves (corridor openapi), or the types lie. Usage: SCRIPT CORRIDOR WEB_DIR
set -euo pipefail
served=$(mktemp)
trap 'rm -f "$served"' EXIT
"$1" openapi > "$served"
python3 - "$served" "$2/src/api/openapi.json" <<'PY'
import json, sys
served = json.load(open(sys.argv[1]))["components"]["schemas"]
web = json.load(open(sys.argv[2]))["components"]["schemas"]
differ = sorted(k for k in set(served) | set(web) if served.get(k) != web.get(k))
if differ:
    print("schemas differ between the server and web/src/api/openapi.json:", ", ".join(differ))
    print("regenerate: build/app/corridor openapi > web/src/api/openapi.json && (cd web && npm run gen:api)")
    sys.exit(1)
print(f"{len(served)} schemas identical")
PY
