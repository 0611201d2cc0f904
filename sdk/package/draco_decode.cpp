// One KHR_draco_mesh_compression buffer into a draco::Mesh, refusing the
// streams that Draco 1.5.5 would decode for an unbounded time.
//
// Draco's texture-coordinate prediction (MeshPredictionSchemeTexCoordsPortable-
// Decoder::DecodePredictionData, mesh_prediction_scheme_tex_coords_portable_
// decoder.h) reads its orientation count as any int32 and decodes that many
// bits from an rANS stream that never runs out: 2^31 bits, a 256 MB
// vector<bool>, seconds of CPU, whatever the mesh's size (the constrained
// multi-parallelogram scheme beside it checks its count against the corners;
// this one does not, upstream either). Any attribute of a stream may name that
// scheme, and it cannot be reached from outside the library. What it needs is
// a parent: the first attribute whose type is POSITION (InitPredictionScheme,
// sequential_attribute_decoder.cc), as do the other parent-predicted schemes
// (geometric normals, the deprecated texture coordinates). So blvd's encoder
// stores positions as a GENERIC attribute (the glTF extension maps attributes
// by unique id, not by Draco type, so any glTF reader still finds them), and
// this decoder refuses a stream that declares a POSITION attribute before its
// values are decoded: no stream it accepts can reach those schemes. Decision
// 0038 has the measurements.
#include "package/glb_detail.h"

#include <draco/compression/config/compression_shared.h>
#include <draco/compression/mesh/mesh_edgebreaker_decoder.h>
#include <draco/compression/mesh/mesh_sequential_decoder.h>
#include <draco/compression/point_cloud/point_cloud_decoder.h>
#include <draco/core/decoder_buffer.h>
#include <draco/mesh/mesh.h>

#include <string>

namespace blvd::package::glb_detail {

namespace {

// A Draco mesh decoder that stops once the stream's attributes are declared
// (their types known, none of their values decoded) if one is a POSITION.
template <class Base>
class ProfileDecoder : public Base {
 public:
  bool refused_position() const { return refused_position_; }

 protected:
  bool DecodeAllAttributes() override {
    const draco::PointCloud* pc = this->point_cloud();
    for (int32_t i = 0; i < pc->num_attributes(); ++i)
      if (pc->attribute(i)->attribute_type() == draco::GeometryAttribute::POSITION) {
        refused_position_ = true;
        return false;
      }
    return Base::DecodeAllAttributes();
  }

 private:
  bool refused_position_ = false;
};

template <class Base>
core::Status decodeWith(draco::DecoderBuffer& db, std::unique_ptr<draco::Mesh>& mesh, std::string& err) {
  ProfileDecoder<Base> dec;
  draco::DecoderOptions options;
  auto out = std::make_unique<draco::Mesh>();
  const draco::Status st = dec.Decode(options, &db, out.get());
  if (dec.refused_position()) {
    err = "Draco data declares a POSITION attribute: blvd's Draco streams store positions as a GENERIC "
          "attribute, and a POSITION would let Draco 1.5.5 decode a texture-coordinate prediction without bound";
    return core::Status::Unsupported;
  }
  if (!st.ok()) {
    err = std::string("Draco decode failed: ") + st.error_msg();
    return core::Status::Corrupt;
  }
  mesh = std::move(out);
  return core::Status::Ok;
}

}  // namespace

core::Status decodeDracoBuffer(const uint8_t* data, size_t size, std::unique_ptr<draco::Mesh>& mesh,
                               std::string& err) {
  draco::DecoderBuffer db;
  db.Init(reinterpret_cast<const char*>(data), size);
  draco::DecoderBuffer peek(db);
  draco::DracoHeader h;
  const draco::Status hs = draco::PointCloudDecoder::DecodeHeader(&peek, &h);
  if (!hs.ok()) {
    err = std::string("Draco header: ") + hs.error_msg();
    return core::Status::Corrupt;
  }
  if (h.encoder_type != draco::TRIANGULAR_MESH) {
    err = "Draco data is not a triangle mesh (encoder type " + std::to_string(h.encoder_type) + ")";
    return core::Status::Unsupported;
  }
  // Only the bitstream our encoder writes: older ones take other decoding
  // paths (below 2.0 a predictor's parent is the final attribute).
  if (h.version_major != 2 || h.version_minor != 2) {
    err = "Draco bitstream " + std::to_string(h.version_major) + "." + std::to_string(h.version_minor) +
          ": blvd reads 2.2 (Draco 1.5)";
    return core::Status::Unsupported;
  }
  if (h.encoder_method == draco::MESH_EDGEBREAKER_ENCODING)
    return decodeWith<draco::MeshEdgebreakerDecoder>(db, mesh, err);
  if (h.encoder_method == draco::MESH_SEQUENTIAL_ENCODING)
    return decodeWith<draco::MeshSequentialDecoder>(db, mesh, err);
  err = "Draco mesh encoding method " + std::to_string(h.encoder_method) + " is unknown";
  return core::Status::Unsupported;
}

}  // namespace blvd::package::glb_detail
