SUMMARY = "C++ library for working with OpenStreetMap data (headers only)"
HOMEPAGE = "https://osmcode.org/libosmium/"
LICENSE = "BSL-1.0"
# Checked against the common licence text: not yet against the source's LICENSE.
LIC_FILES_CHKSUM = "file://${COMMON_LICENSE_DIR}/BSL-1.0;md5=65a7df9ad57aacf825fd252c4c33288c"

# 2.19.0 is what Debian 12 ships (libosmium2-dev 2.19.0-1).
SRC_URI = "https://github.com/osmcode/libosmium/archive/v${PV}.tar.gz;downloadfilename=${BP}.tar.gz"
# Not recorded yet: the first fetch prints it.
# SRC_URI[sha256sum] = ""

DEPENDS = "boost protozero expat zlib bzip2"

inherit cmake

EXTRA_OECMAKE = "-DBUILD_EXAMPLES=OFF -DBUILD_TESTING=OFF -DBUILD_BENCHMARKS=OFF -DBUILD_DATA_TESTS=OFF"

ALLOW_EMPTY:${PN} = "1"
