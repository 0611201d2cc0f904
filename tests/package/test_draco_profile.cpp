// The Draco streams the GLB reader accepts (sdk/package/draco_decode.cpp):
// bitstream 2.2 and no attribute of Draco type POSITION, whichever of Draco's
// mesh decoders (sequential, edgebreaker standard or valence) the stream
// names. The streams here come from Draco's own encoder, so each case is one
// Draco itself writes.
#include <gtest/gtest.h>

#include <draco/compression/encode.h>
#include <draco/core/encoder_buffer.h>
#include <draco/mesh/mesh.h>

#include <string>
#include <vector>

#include "package/glb_detail.h"

namespace blvd::package {
namespace {

// A 6 x 6 grid of quads with uvs, positions typed `pos_type`.
std::vector<uint8_t> encodeGrid(draco::GeometryAttribute::Type pos_type, int speed) {
  const int n = 6, verts = (n + 1) * (n + 1);
  draco::Mesh dm;
  dm.set_num_points(verts);
  auto add = [&](draco::GeometryAttribute::Type type, int comps) {
    draco::GeometryAttribute ga;
    ga.Init(type, nullptr, static_cast<uint8_t>(comps), draco::DT_FLOAT32, false, comps * 4, 0);
    return dm.attribute(dm.AddAttribute(ga, true, verts));
  };
  draco::PointAttribute* pos = add(pos_type, 3);
  draco::PointAttribute* uv = add(draco::GeometryAttribute::TEX_COORD, 2);
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x) {
      const draco::AttributeValueIndex i(z * (n + 1) + x);
      const float p[3] = {x * 1.0f, 0.1f * x * z, z * 1.0f}, t[2] = {x / float(n), z / float(n)};
      pos->SetAttributeValue(i, p);
      uv->SetAttributeValue(i, t);
    }
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = z * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      dm.AddFace({draco::PointIndex(a), draco::PointIndex(b), draco::PointIndex(d)});
      dm.AddFace({draco::PointIndex(a), draco::PointIndex(d), draco::PointIndex(c)});
    }
  draco::Encoder enc;
  enc.SetAttributeQuantization(pos_type, 14);
  enc.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, 12);
  enc.SetSpeedOptions(speed, speed);
  if (pos_type != draco::GeometryAttribute::POSITION) enc.options().SetGlobalBool("split_mesh_on_seams", true);
  draco::EncoderBuffer eb;
  EXPECT_TRUE(enc.EncodeMeshToBuffer(dm, &eb).ok());
  return std::vector<uint8_t>(eb.data(), eb.data() + eb.size());
}

core::Status decode(const std::vector<uint8_t>& s, std::string& err) {
  std::unique_ptr<draco::Mesh> mesh;
  return glb_detail::decodeDracoBuffer(s.data(), s.size(), mesh, err);
}

// Speed 10 is Draco's sequential mesh coding, 5 the standard edgebreaker, 3
// the valence one with the texture-coordinate prediction (on POSITION).
TEST(DracoProfile, APositionTypedAttributeIsRefusedByEveryMeshDecoder) {
  for (int speed : {10, 5, 3}) {
    std::string err;
    EXPECT_EQ(decode(encodeGrid(draco::GeometryAttribute::POSITION, speed), err), core::Status::Unsupported)
        << "speed " << speed;
    EXPECT_NE(err.find("declares a POSITION attribute"), std::string::npos) << "speed " << speed << ": " << err;
  }
}

TEST(DracoProfile, GenericPositionsDecode) {
  for (int speed : {10, 5, 3}) {
    std::string err;
    std::unique_ptr<draco::Mesh> mesh;
    const std::vector<uint8_t> s = encodeGrid(draco::GeometryAttribute::GENERIC, speed);
    ASSERT_EQ(glb_detail::decodeDracoBuffer(s.data(), s.size(), mesh, err), core::Status::Ok) << speed << ": " << err;
    EXPECT_EQ(mesh->num_faces(), 72u);
    EXPECT_EQ(mesh->num_attributes(), 2);
  }
}

// Bytes 5 and 6 of a Draco header are the bitstream's major and minor version.
TEST(DracoProfile, OnlyBitstream22IsRead) {
  std::vector<uint8_t> s = encodeGrid(draco::GeometryAttribute::GENERIC, 5);
  ASSERT_EQ(s[5], 2);
  ASSERT_EQ(s[6], 2);
  s[6] = 1;
  std::string err;
  EXPECT_EQ(decode(s, err), core::Status::Unsupported);
  EXPECT_NE(err.find("Draco bitstream 2.1: blvd reads 2.2"), std::string::npos) << err;
  const std::vector<uint8_t> junk = {'D', 'R', 'A'};
  EXPECT_EQ(decode(junk, err), core::Status::Corrupt);
  EXPECT_NE(err.find("Draco header"), std::string::npos) << err;
}

}  // namespace
}  // namespace blvd::package
