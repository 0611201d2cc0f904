# A sample configured on its own against an installed SDK
# (cmake -S samples/<name> -B build -DCMAKE_PREFIX_PATH=<prefix>) includes this after
# its project(): it finds what the in-tree build gets from the top-level
# CMakeLists.txt. Set BLVD_SAMPLE_COMPONENTS first (e.g. "adapters") for more
# than libblvd.
set(CMAKE_CXX_STANDARD 17)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
find_package(blvd 0.1 REQUIRED COMPONENTS ${BLVD_SAMPLE_COMPONENTS})
find_package(nlohmann_json REQUIRED)
find_package(CLI11 REQUIRED)
find_path(STB_INCLUDE_DIRS stb_image_write.h PATH_SUFFIXES stb REQUIRED)
set(BLVD_BUILD_TESTS OFF)  # the samples' tests need the source tree's fixtures
# samples/common, which the in-tree build adds from samples/CMakeLists.txt.
add_subdirectory(${CMAKE_CURRENT_LIST_DIR} ${CMAKE_BINARY_DIR}/samples-common)
