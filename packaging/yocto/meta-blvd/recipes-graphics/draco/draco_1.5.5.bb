SUMMARY = "Draco 3D geometric mesh and point cloud compression"
HOMEPAGE = "https://google.github.io/draco/"
LICENSE = "Apache-2.0"
# Checked against the common licence text: not yet against the source's LICENSE.
LIC_FILES_CHKSUM = "file://${COMMON_LICENSE_DIR}/Apache-2.0;md5=89aea4e17d99a7cacdbeed46a0096b10"

# 1.5.5 is what Debian 12 ships (libdraco-dev 1.5.5+dfsg-2).
SRC_URI = "https://github.com/google/draco/archive/${PV}.tar.gz;downloadfilename=${BP}.tar.gz"
SRC_URI[sha256sum] = "6b7994150bbc513abcdbe22ad778d6b2df10fc8cdc7035e916985b2a209ab826"

inherit cmake

EXTRA_OECMAKE = "-DBUILD_SHARED_LIBS=ON -DDRACO_TESTS=OFF"
