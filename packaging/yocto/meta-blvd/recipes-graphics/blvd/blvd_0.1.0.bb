SUMMARY = "Street-level city rendering SDK for in-vehicle displays"
DESCRIPTION = "libblvd (C99 API) renders the street view of a city baked from \
OpenStreetMap, headless through EGL or into the host's GL context, and tracks \
the vehicle from GNSS and CAN. Also the blvd tool and the device adapters."
SECTION = "libs"

# The repository states no licence for blvd's own code yet (no LICENSE file,
# README.md names none). The DBC files in blvd-tools are MIT (opendbc), and
# /usr/bin/blvd compiles in CGAL code under GPL-3.0-or-later.
LICENSE = "CLOSED"

# Placeholder: blvd's git URL is not public yet. Point SRC_URI at your mirror
# and SRCREV at the release commit, or build a checkout with externalsrc:
#   INHERIT += "externalsrc"
#   EXTERNALSRC:pn-blvd = "/path/to/blvd"
SRC_URI = "git://git.example.org/blvd/blvd.git;protocol=https;branch=main"
SRCREV = "0000000000000000000000000000000000000000"
S = "${WORKDIR}/git"

inherit cmake pkgconfig

# One entry per dependency, with the layer that provides its recipe. The
# recipes in this layer are for dependencies not found in openembedded-core or
# meta-oe (not searched exhaustively: drop ours where an upstream one exists).
# tests/packaging/check_recipe.py checks this list against the CMake files.

# glm (find_package glm): meta-oe
DEPENDS += "glm"
# draco (find_package draco): this layer
DEPENDS += "draco"
# meshoptimizer (find_package meshoptimizer): this layer
DEPENDS += "meshoptimizer"
# geographiclib (find_package GeographicLib): this layer (meta-ros has one)
DEPENDS += "geographiclib"
# zstd (find_package zstd): openembedded-core
DEPENDS += "zstd"
# nlohmann-json (find_package nlohmann_json): meta-oe
DEPENDS += "nlohmann-json"
# cli11 (find_package CLI11): meta-oe
DEPENDS += "cli11"
# zlib (find_package ZLIB): openembedded-core
DEPENDS += "zlib"
# curl (find_package CURL): openembedded-core
DEPENDS += "curl"
# virtual/egl (find_package OpenGL COMPONENTS EGL): openembedded-core (mesa) or the BSP
DEPENDS += "virtual/egl"
# virtual/libgles2 (GLES3/gl3.h in sdk/render): openembedded-core (mesa) or the BSP
DEPENDS += "virtual/libgles2"
# stb (pkg-config stb): this layer (meta-imx has one, without stb.pc)
DEPENDS += "stb"
# libwebp (pkg-config libwebp): openembedded-core
DEPENDS += "libwebp"

EXTRA_OECMAKE = "\
    -DCMAKE_BUILD_TYPE=Release \
    -DBLVD_BUILD_TESTS=OFF \
    -DBLVD_SANITIZE=OFF \
    -DBLVD_TSAN=OFF \
    -DCMAKE_MODULE_PATH=${STAGING_DATADIR}/cmake/geographiclib \
"
# CMakeLists.txt appends the build host's /usr/share/cmake/geographiclib to
# CMAKE_MODULE_PATH; the sysroot's FindGeographicLib.cmake (installed there by
# this layer's geographiclib) comes first.

# tools: the bake and /usr/bin/blvd (package blvd-tools), on a build host or a
#   development image; a vehicle image needs only libblvd0. Its dependencies:
#   cgal (this layer) with gmp, mpfr, boost (openembedded-core); libosmium and
#   protozero (header-only, this layer); bzip2, expat, openssl (openembedded-core); libzip (meta-oe).
# osmesa: the software backend; mesa (openembedded-core) built with
#   PACKAGECONFIG:append:pn-mesa = " osmesa". Without it, the osmesa backend
#   fails at create and Auto uses EGL only.
# EGL has no switch: it is the runtime's backend (virtual/egl above), and the
# host-context path gets its GL functions through it.
PACKAGECONFIG ??= "tools osmesa"
PACKAGECONFIG[tools] = "-DBLVD_BUILD_TOOLS=ON,-DBLVD_BUILD_TOOLS=OFF,cgal gmp mpfr boost libosmium protozero bzip2 expat openssl libzip"
PACKAGECONFIG[osmesa] = "-DBLVD_WITH_OSMESA=ON,-DBLVD_WITH_OSMESA=OFF,mesa"
PACKAGECONFIG[werror] = "-DBLVD_WERROR=ON,-DBLVD_WERROR=OFF"
# The samples build only (none is installed); host_context needs glesv2.
PACKAGECONFIG[samples] = "-DBLVD_BUILD_SAMPLES=ON,-DBLVD_BUILD_SAMPLES=OFF,virtual/libgles2"

# The same split as packaging/debian/control.
PACKAGES =+ "libblvd0 libblvd-dev blvd-tools libblvd-adapters-dev"

FILES:libblvd0 = "${libdir}/libblvd.so.*"
FILES:libblvd-dev = "\
    ${includedir}/blvd/*.h \
    ${libdir}/libblvd.so \
    ${libdir}/cmake/blvd/blvdConfig.cmake \
    ${libdir}/cmake/blvd/blvdConfigVersion.cmake \
    ${libdir}/cmake/blvd/blvdTargets*.cmake \
    ${libdir}/pkgconfig/blvd.pc \
"
FILES:blvd-tools = "${bindir}/blvd ${datadir}/blvd ${mandir}/man1/blvd.1"
FILES:libblvd-adapters-dev = "\
    ${includedir}/blvd/adapters \
    ${includedir}/blvd/internal \
    ${libdir}/libblvd_adapter_*.a \
    ${libdir}/libblvd_internals.a \
    ${libdir}/cmake/blvd/blvdAdaptersTargets*.cmake \
    ${libdir}/pkgconfig/blvd-adapters.pc \
    ${libdir}/pkgconfig/blvd-internals.pc \
"

RDEPENDS:libblvd-dev = "libblvd0"
RDEPENDS:libblvd-adapters-dev = "libblvd-dev"
# Static archives by design (the adapters and blvd_internals).
INSANE_SKIP:libblvd-adapters-dev += "staticdev"
