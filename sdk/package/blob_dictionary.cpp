// The dictionary of blob frames made with kBlobZstdDict (package format
// 6.0): glTF JSON as the GLB encoder writes it, a block's levels and an
// impostor layer's (one capture, then several), as zstd raw content (RFC
// 8878 §5: any bytes may be a dictionary). An impostor layer is a few kB and
// its JSON a third of it, so without a dictionary zstd finds little to match
// within one blob (decision 0041).
//
// FROZEN: a package decodes only with these exact bytes. Another dictionary
// takes another BIDX flag.
#include "package/blob_dictionary.h"

#include <cstring>

namespace blvd::package {

namespace {

// clang-format off
const char kDictionary[] =
    "{\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":21,\"max\":[-5437.765625,0.0625,960.8125],\""
    "min\":[-5507.546875,0.03125,921.015625],\"type\":\"VEC3\"},{\"bufferView\":1,\"componentType\":5122,\"count\":2"
    "1,\"normalized\":true,\"type\":\"VEC3\"},{\"bufferView\":2,\"componentType\":5121,\"count\":21,\"normalized\":true"
    ",\"type\":\"VEC4\"},{\"bufferView\":3,\"componentType\":5123,\"count\":39,\"type\":\"SCALAR\"},{\"bufferView\":4,\"co"
    "mponentType\":5126,\"count\":12,\"max\":[-5437.84375,0.0625,960.8125],\"min\":[-5507.546875,0.03125,922.031"
    "25],\"type\":\"VEC3\"},{\"bufferView\":5,\"componentType\":5122,\"count\":12,\"normalized\":true,\"type\":\"VEC3\"},"
    "{\"bufferView\":6,\"componentType\":5121,\"count\":12,\"normalized\":true,\"type\":\"VEC4\"},{\"bufferView\":7,\"co"
    "mponentType\":5123,\"count\":18,\"type\":\"SCALAR\"},{\"bufferView\":8,\"componentType\":5126,\"count\":7,\"max\":["
    "-5437.890625,0.0625,960.8125],\"min\":[-5505.46875,0.03125,922.03125],\"type\":\"VEC3\"},{\"bufferView\":9,\""
    "componentType\":5122,\"count\":7,\"normalized\":true,\"type\":\"VEC3\"},{\"bufferView\":10,\"componentType\":5121"
    ",\"count\":7,\"normalized\":true,\"type\":\"VEC4\"},{\"bufferView\":11,\"componentType\":5123,\"count\":9,\"type\":\""
    "SCALAR\"},{\"bufferView\":12,\"componentType\":5126,\"count\":3,\"max\":[-5437.890625,0.03125,960.671875],\"mi"
    "n\":[-5505.46875,0.03125,922.03125],\"type\":\"VEC3\"},{\"bufferView\":13,\"componentType\":5122,\"count\":3,\"n"
    "ormalized\":true,\"type\":\"VEC3\"},{\"bufferView\":14,\"componentType\":5121,\"count\":3,\"normalized\":true,\"ty"
    "pe\":\"VEC4\"},{\"bufferView\":15,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}],\"asset\":{\"generator\":\""
    "blvd\",\"version\":\"2.0\"},\"bufferViews\":[{\"buffer\":1,\"byteLength\":252,\"byteOffset\":0,\"byteStride\":12,\"e"
    "xtensions\":{\"EXT_meshopt_compression\":{\"buffer\":0,\"byteLength\":131,\"byteOffset\":0,\"byteStride\":12,\"c"
    "ount\":21,\"filter\":\"EXPONENTIAL\",\"mode\":\"ATTRIBUTES\"}},\"target\":34962},{\"buffer\":1,\"byteLength\":168,\""
    "byteOffset\":252,\"byteStride\":8,\"extensions\":{\"EXT_meshopt_compression\":{\"buffer\":0,\"byteLength\":41,\""
    "byteOffset\":132,\"byteStride\":8,\"count\":21,\"filter\":\"OCTAHEDRAL\",\"mode\":\"ATTRIBUTES\"}},\"target\":34962"
    "},{\"buffer\":1,\"byteLength\":84,\"byteOffset\":420,\"byteStride\":4,\"extensions\":{\"EXT_meshopt_compression"
    "\":{\"buffer\":0,\"byteLength\":52,\"byteOffset\":176,\"byteStride\":4,\"count\":21,\"mode\":\"ATTRIBUTES\"}},\"targ"
    "et\":34962},{\"buffer\":1,\"byteLength\":78,\"byteOffset\":504,\"extensions\":{\"EXT_meshopt_compression\":{\"bu"
    "ffer\":0,\"byteLength\":30,\"byteOffset\":228,\"byteStride\":2,\"count\":39,\"mode\":\"TRIANGLES\"}},\"target\":349"
    "63},{\"buffer\":1,\"byteLength\":144,\"byteOffset\":584,\"byteStride\":12,\"extensions\":{\"EXT_meshopt_compres"
    "sion\":{\"buffer\":0,\"byteLength\":99,\"byteOffset\":260,\"byteStride\":12,\"count\":12,\"filter\":\"EXPONENTIAL\""
    "\n"
    "{\"accessors\":[{\"componentType\":5123,\"count\":429,\"type\":\"SCALAR\"},{\"componentType\":5126,\"count\":203,\""
    "max\":[-1023.9493408203125,13.593968391418457,-73.9024658203125],\"min\":[-1377.0767822265625,-2.210965"
    "871810913,-778.5015258789063],\"type\":\"VEC3\"}],\"asset\":{\"generator\":\"blvd\",\"version\":\"2.0\"},\"bufferVi"
    "ews\":[{\"buffer\":0,\"byteLength\":1008,\"byteOffset\":0},{\"buffer\":0,\"byteLength\":64,\"byteOffset\":1008},{"
    "\"buffer\":0,\"byteLength\":1342,\"byteOffset\":1072}],\"buffers\":[{\"byteLength\":2414}],\"extensionsRequired"
    "\":[\"KHR_draco_mesh_compression\",\"BLVD_projected_texcoords\",\"EXT_texture_webp\"],\"extensionsUsed\":[\"KH"
    "R_draco_mesh_compression\",\"BLVD_projected_texcoords\",\"EXT_texture_webp\",\"KHR_materials_unlit\"],\"imag"
    "es\":[{\"bufferView\":2,\"mimeType\":\"image/webp\"}],\"materials\":[{\"doubleSided\":false,\"extensions\":{\"KHR_"
    "materials_unlit\":{}},\"pbrMetallicRoughness\":{\"baseColorFactor\":[1.0,1.0,1.0,1.0],\"baseColorTexture\":"
    "{\"index\":0},\"metallicFactor\":0.0,\"roughnessFactor\":1.0}}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"P"
    "OSITION\":1},\"extensions\":{\"BLVD_projected_texcoords\":{\"bufferView\":1,\"count\":1},\"KHR_draco_mesh_comp"
    "ression\":{\"attributes\":{\"POSITION\":0},\"bufferView\":0}},\"indices\":0,\"material\":0,\"mode\":4}]}],\"nodes\""
    ":[{\"mesh\":0}],\"samplers\":[{\"magFilter\":9729,\"minFilter\":9987,\"wrapS\":33071,\"wrapT\":33071}],\"scene\":0"
    ",\"scenes\":[{\"nodes\":[0]}],\"textures\":[{\"extensions\":{\"EXT_texture_webp\":{\"source\":0}},\"sampler\":0}]}"
    "\n"
    "{\"accessors\":[{\"componentType\":5123,\"count\":903,\"type\":\"SCALAR\"},{\"componentType\":5126,\"count\":422,\""
    "max\":[504.04443359375,13.937504768371582,168.789794921875],\"min\":[-1378.471435546875,-2.148938179016"
    "1133,-679.9998168945313],\"type\":\"VEC3\"},{\"componentType\":5121,\"count\":422,\"type\":\"SCALAR\"}],\"asset\":"
    "{\"generator\":\"blvd\",\"version\":\"2.0\"},\"bufferViews\":[{\"buffer\":0,\"byteLength\":1742,\"byteOffset\":0},{\""
    "buffer\":0,\"byteLength\":192,\"byteOffset\":1744},{\"buffer\":0,\"byteLength\":2108,\"byteOffset\":1936}],\"buf"
    "fers\":[{\"byteLength\":4044}],\"extensionsRequired\":[\"KHR_draco_mesh_compression\",\"BLVD_projected_texco"
    "ords\",\"EXT_texture_webp\"],\"extensionsUsed\":[\"KHR_draco_mesh_compression\",\"BLVD_projected_texcoords\","
    "\"EXT_texture_webp\",\"KHR_materials_unlit\"],\"images\":[{\"bufferView\":2,\"mimeType\":\"image/webp\"}],\"mater"
    "ials\":[{\"doubleSided\":false,\"extensions\":{\"KHR_materials_unlit\":{}},\"pbrMetallicRoughness\":{\"baseCol"
    "orFactor\":[1.0,1.0,1.0,1.0],\"baseColorTexture\":{\"index\":0},\"metallicFactor\":0.0,\"roughnessFactor\":1."
    "0}}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":1,\"_SHOT\":2},\"extensions\":{\"BLVD_projected_t"
    "excoords\":{\"bufferView\":1,\"count\":3},\"KHR_draco_mesh_compression\":{\"attributes\":{\"POSITION\":0,\"_SHOT"
    "\":1},\"bufferView\":0}},\"indices\":0,\"material\":0,\"mode\":4}]}],\"nodes\":[{\"mesh\":0}],\"samplers\":[{\"magFi"
    "lter\":9729,\"minFilter\":9987,\"wrapS\":33071,\"wrapT\":33071}],\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"textur"
    "es\":[{\"extensions\":{\"EXT_texture_webp\":{\"source\":0}},\"sampler\":0}]}";
// clang-format on

}  // namespace

BlobDictionary glbDictionary() { return {kDictionary, sizeof kDictionary - 1}; }

}  // namespace blvd::package
