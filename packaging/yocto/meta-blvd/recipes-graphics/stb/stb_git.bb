SUMMARY = "Single-file public domain libraries for C/C++ (headers only)"
HOMEPAGE = "https://github.com/nothings/stb"
LICENSE = "MIT | Unlicense"
# Checked against the common licence text: not yet against the source's LICENSE.
LIC_FILES_CHKSUM = "file://${COMMON_LICENSE_DIR}/MIT;md5=0835ade698e0bcf8506ecda2f7b4f302"

# The snapshot Debian 12 ships (libstb-dev 0.0~git20220908.8b5f1f3+ds-1).
PV = "0.0+git20220908"
SRC_URI = "git://github.com/nothings/stb.git;protocol=https;branch=master"
SRCREV = "8b5f1f37b5b75829fc72d38e7b5d4bcbf8a26d55"
S = "${WORKDIR}/git"

# Headers in ${includedir}/stb and an stb.pc as Debian's (pkg_check_modules(STB ... stb)),
# without -lstb: blvd compiles the implementations it uses itself.
do_install() {
    install -d ${D}${includedir}/stb ${D}${libdir}/pkgconfig
    install -m 0644 ${S}/*.h ${D}${includedir}/stb/
    cat > ${D}${libdir}/pkgconfig/stb.pc <<PC
Name: stb
Description: single-file image libraries for C/C++ (headers)
Version: ${PV}
Cflags: -I${includedir}/stb
PC
}

ALLOW_EMPTY:${PN} = "1"
