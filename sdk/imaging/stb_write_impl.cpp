// The project's only stb_image_write implementation (PNG frames, the bake's
// JPEG impostor textures): tools only, not in libblvd. stb_image's is
// sdk/render/stb_impl.cpp.
#define STB_IMAGE_WRITE_IMPLEMENTATION

#define BLVD_STB_IMAGE_WRITE
#include "core/third_party_stb.h"
