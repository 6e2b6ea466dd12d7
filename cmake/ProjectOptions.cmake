# Warnings and sanitizers apply to the project's own targets only, through this interface target.
add_library(corridor_options INTERFACE)
target_compile_options(corridor_options INTERFACE -Wall -Wextra -Werror -Wpedantic -Wshadow
                       -Wnon-virtual-dtor -Wcast-align -Woverloaded-virtual)
target_include_directories(corridor_options INTERFACE ${PROJECT_SOURCE_DIR})
if(CORRIDOR_SANITIZE)
  target_compile_options(corridor_options INTERFACE -fsanitize=address,undefined
                         -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(corridor_options INTERFACE -fsanitize=address,undefined)
endif()
option(CORRIDOR_TSAN "Build with ThreadSanitizer" OFF)
if(CORRIDOR_TSAN)
  # -Wno-tsan: GCC warns that Asio's atomic_thread_fence is invisible to TSan (library code).
  target_compile_options(corridor_options INTERFACE -fsanitize=thread -fno-omit-frame-pointer -Wno-tsan)
  target_link_options(corridor_options INTERFACE -fsanitize=thread)
endif()
if(CORRIDOR_FUZZ)
  # Coverage instrumentation in every project library, so libFuzzer sees into the request path.
  target_compile_options(corridor_options INTERFACE -fsanitize=fuzzer-no-link)
endif()
