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
