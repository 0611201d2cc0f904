SUMMARY = "Computational Geometry Algorithms Library (headers only)"
HOMEPAGE = "https://www.cgal.org"
# Per package: blvd's bake uses GPL-3.0-or-later ones (Arrangement_on_surface_2,
# Triangulation_2) and the LGPL-3.0-or-later kernel.
LICENSE = "GPL-3.0-or-later & LGPL-3.0-or-later"
# Checked against the common licence texts: not yet against the source's LICENSE.
LIC_FILES_CHKSUM = "file://${COMMON_LICENSE_DIR}/GPL-3.0-or-later;md5=1c76c4cc354acaac30ed4d5eefea7245 \
                    file://${COMMON_LICENSE_DIR}/LGPL-3.0-or-later;md5=c51d3eef3be114124d11349ca0d7e117"

# 5.5.1 is what Debian 12 ships (libcgal-dev 5.5.1-2).
SRC_URI = "https://github.com/CGAL/cgal/releases/download/v${PV}/CGAL-${PV}.tar.xz"
# Not recorded yet: the first fetch prints it.
# SRC_URI[sha256sum] = ""
S = "${WORKDIR}/CGAL-${PV}"

DEPENDS = "boost gmp mpfr"

inherit cmake

ALLOW_EMPTY:${PN} = "1"
FILES:${PN}-dev += "${libdir}/cmake ${datadir}/cmake"
