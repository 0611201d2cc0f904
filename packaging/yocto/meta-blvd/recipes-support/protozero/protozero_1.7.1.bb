SUMMARY = "Minimalist protocol buffer decoder and encoder in C++ (headers only)"
HOMEPAGE = "https://github.com/mapbox/protozero"
LICENSE = "BSD-2-Clause"
# Checked against the common licence text: not yet against the source's LICENSE.md.
LIC_FILES_CHKSUM = "file://${COMMON_LICENSE_DIR}/BSD-2-Clause;md5=cb641bc04cda31daea161b1bc15da69f"

# 1.7.1 is what Debian 12 ships (libprotozero-dev 1.7.1-1).
SRC_URI = "https://github.com/mapbox/protozero/archive/v${PV}.tar.gz;downloadfilename=${BP}.tar.gz"
SRC_URI[sha256sum] = "27e0017d5b3ba06d646a3ec6391d5ccc8500db821be480aefd2e4ddc3de5ff99"

inherit cmake

EXTRA_OECMAKE = "-DBUILD_TESTING=OFF"

ALLOW_EMPTY:${PN} = "1"
