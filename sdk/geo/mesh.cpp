#include "geo/mesh.h"

namespace blvd::geo {

void MeshData::append(const MeshData& o) {
  const auto base = static_cast<uint32_t>(vertexCount());
  positions.insert(positions.end(), o.positions.begin(), o.positions.end());
  normals.insert(normals.end(), o.normals.begin(), o.normals.end());
  colors.insert(colors.end(), o.colors.begin(), o.colors.end());
  texcoords.insert(texcoords.end(), o.texcoords.begin(), o.texcoords.end());
  indices.reserve(indices.size() + o.indices.size());
  for (uint32_t i : o.indices) indices.push_back(base + i);
}

}  // namespace blvd::geo
