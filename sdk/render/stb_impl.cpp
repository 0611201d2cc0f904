// The project's only stb_image implementation (decoding: the runtime's
// impostor textures, and PNG reading in sdk/imaging). Every other file
// includes the header without the IMPLEMENTATION macro; a second definition
// would be a duplicate symbol. stb_image_write's is sdk/imaging/stb_write_impl.cpp
// (tools only, not in libblvd).
#define STB_IMAGE_IMPLEMENTATION

#define BLVD_STB_IMAGE
#include "core/third_party_stb.h"
