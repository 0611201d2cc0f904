// The OSMesa backend in a build without it (BLVD_WITH_OSMESA=OFF): creating
// it fails with the reason, and Backend::Auto goes on without it.
#include "render/context.h"

namespace blvd::render {

std::unique_ptr<Context> createOSMesaContext(std::string& why) {
  why += "osmesa: not in this build (BLVD_WITH_OSMESA=OFF)\n";
  return nullptr;
}

}  // namespace blvd::render
