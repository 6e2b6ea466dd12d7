// The API's data shapes as OpenAPI 3 schemas (server/openapi_schemas.json, compiled in), served in
// /v1/openapi.json under components.schemas; the console's types are generated from them.
#pragma once

#include <string_view>

namespace corridor::server {

std::string_view openapi_schemas_json();

}  // namespace corridor::server
