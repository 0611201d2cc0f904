SUMMARY = "Mesh optimization library that makes meshes smaller and faster to render"
HOMEPAGE = "https://github.com/zeux/meshoptimizer"
LICENSE = "MIT"
# Checked against the common licence text: not yet against the source's LICENSE.md.
LIC_FILES_CHKSUM = "file://${COMMON_LICENSE_DIR}/MIT;md5=0835ade698e0bcf8506ecda2f7b4f302"

# 0.18 is what Debian 12 ships (libmeshoptimizer-dev 0.18+dfsg-2).
SRC_URI = "https://github.com/zeux/meshoptimizer/archive/v${PV}.tar.gz;downloadfilename=${BP}.tar.gz"
SRC_URI[sha256sum] = "f5bc07d7322e6292fe0afce03462b5c394d111386236f926fdc44d2aff3b854b"

inherit cmake

EXTRA_OECMAKE = "-DMESHOPT_BUILD_SHARED_LIBS=ON"
