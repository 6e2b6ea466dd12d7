# Finds SUMO's C++ client libraries and defines SUMO::libtracicpp (TraCI over a socket) and
# SUMO::libsumocpp (SUMO in-process).
#
# Debian 12's sumo package ships /usr/share/sumo/cmake/SUMOConfig.cmake, but that file derives its
# install prefix from its own location (/usr/share/sumo) and then fails on libraries that really
# live in /usr/lib/<arch>. This module wins over it (module mode is tried first) and finds the
# same files where Debian puts them.
find_path(SUMO_INCLUDE_DIR libsumo/libtraci.h)
find_library(SUMO_LIBTRACICPP_LIBRARY NAMES tracicpp libtracicpp)
find_library(SUMO_LIBSUMOCPP_LIBRARY NAMES sumocpp libsumocpp)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(SUMO REQUIRED_VARS SUMO_LIBTRACICPP_LIBRARY SUMO_LIBSUMOCPP_LIBRARY SUMO_INCLUDE_DIR)

if(SUMO_FOUND AND NOT TARGET SUMO::libtracicpp)
  add_library(SUMO::libtracicpp UNKNOWN IMPORTED)
  set_target_properties(SUMO::libtracicpp PROPERTIES IMPORTED_LOCATION "${SUMO_LIBTRACICPP_LIBRARY}"
                        INTERFACE_INCLUDE_DIRECTORIES "${SUMO_INCLUDE_DIR}")
  add_library(SUMO::libsumocpp UNKNOWN IMPORTED)
  set_target_properties(SUMO::libsumocpp PROPERTIES IMPORTED_LOCATION "${SUMO_LIBSUMOCPP_LIBRARY}"
                        INTERFACE_INCLUDE_DIRECTORIES "${SUMO_INCLUDE_DIR}")
endif()
mark_as_advanced(SUMO_INCLUDE_DIR SUMO_LIBTRACICPP_LIBRARY SUMO_LIBSUMOCPP_LIBRARY)
