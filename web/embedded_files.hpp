// The dispatch console's built files (web/), compiled into the executable so that `corridor serve`
// needs no directory beside it. The build generates the definition from `npm run build`'s output.
#pragma once

#include <cstddef>
#include <span>

namespace corridor::web {

struct EmbeddedFile {
  const char* path;  // URL path: "/index.html", "/assets/index-3f2a.js"
  const unsigned char* data;
  std::size_t size;
};

std::span<const EmbeddedFile> embedded_files();

}  // namespace corridor::web
