SUMMARY = "C++ classes for geodesic and geographic coordinate conversions"
HOMEPAGE = "https://geographiclib.sourceforge.io"
LICENSE = "MIT"
# Checked against the common licence text: not yet against the source's LICENSE.txt.
LIC_FILES_CHKSUM = "file://${COMMON_LICENSE_DIR}/MIT;md5=0835ade698e0bcf8506ecda2f7b4f302"

# 2.1.2 is what Debian 12 ships (libgeographiclib-dev 2.1.2-1).
SRC_URI = "${SOURCEFORGE_MIRROR}/geographiclib/distrib-C++/GeographicLib-${PV}.tar.gz"
SRC_URI[sha256sum] = "b062b472dae3d371b3005f4ea2fc59af687b8ea76eb23df732ec11c500fba959"
S = "${WORKDIR}/GeographicLib-${PV}"

inherit cmake

EXTRA_OECMAKE = "-DBUILD_DOCUMENTATION=OFF -DBUILD_MANPAGES=OFF"

# blvd's CMakeLists.txt uses FindGeographicLib.cmake where Debian puts it.
do_install:append() {
    install -Dm 0644 ${S}/cmake/FindGeographicLib.cmake ${D}${datadir}/cmake/geographiclib/FindGeographicLib.cmake
}

PACKAGE_BEFORE_PN += "${PN}-tools"
FILES:${PN}-tools = "${bindir} ${sbindir}"
FILES:${PN}-dev += "${datadir}/cmake"
