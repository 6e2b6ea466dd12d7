# Every third-party dependency comes from Debian 12 packages; scripts/setup.sh installs them.
find_package(Threads REQUIRED)
find_package(ZLIB REQUIRED)
find_package(BZip2 REQUIRED)
find_package(EXPAT REQUIRED)
find_package(Boost 1.74 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(spdlog REQUIRED)
find_package(fmt REQUIRED)
find_package(SQLite3 REQUIRED)
# SUMO 1.15 (packages sumo, sumo-tools): the closed loop talks TraCI through libtracicpp.
list(APPEND CMAKE_MODULE_PATH "${PROJECT_SOURCE_DIR}/cmake")
find_package(SUMO REQUIRED)
# The localizer's stereo odometry: OpenCV 4.6 core modules (no contrib), Eigen and Ceres.
find_package(OpenCV 4.5 REQUIRED COMPONENTS core imgproc imgcodecs features2d calib3d)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Ceres 2.0 REQUIRED)

# Debian ships GeographicLib without a CMake config; find the library and header directly.
find_library(GEOGRAPHICLIB_LIBRARY NAMES GeographicLib REQUIRED)
find_path(GEOGRAPHICLIB_INCLUDE_DIR GeographicLib/LocalCartesian.hpp REQUIRED)
add_library(corridor_geographiclib INTERFACE)
target_link_libraries(corridor_geographiclib INTERFACE ${GEOGRAPHICLIB_LIBRARY})
target_include_directories(corridor_geographiclib SYSTEM INTERFACE ${GEOGRAPHICLIB_INCLUDE_DIR})

# METIS (nested-dissection order for the contraction hierarchy): no CMake config in Debian either.
find_library(METIS_LIBRARY NAMES metis REQUIRED)
find_path(METIS_INCLUDE_DIR metis.h REQUIRED)
add_library(corridor_metis INTERFACE)
target_link_libraries(corridor_metis INTERFACE ${METIS_LIBRARY})
target_include_directories(corridor_metis SYSTEM INTERFACE ${METIS_INCLUDE_DIR})

# libosmium is header-only; it needs protozero (PBF) and the compression/XML libraries.
find_path(OSMIUM_INCLUDE_DIR osmium/osm.hpp REQUIRED)
find_path(PROTOZERO_INCLUDE_DIR protozero/pbf_reader.hpp REQUIRED)
add_library(corridor_osmium INTERFACE)
target_include_directories(corridor_osmium SYSTEM INTERFACE ${OSMIUM_INCLUDE_DIR} ${PROTOZERO_INCLUDE_DIR})
target_link_libraries(corridor_osmium INTERFACE ZLIB::ZLIB BZip2::BZip2 EXPAT::EXPAT Threads::Threads)

if(CORRIDOR_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
find_package(benchmark REQUIRED)
