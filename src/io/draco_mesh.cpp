#include <lightvol/io/draco_mesh.h>

#include <lightvol/check/topology.h>

namespace lightvol::detail {

Mesh from_draco(const draco::Mesh& in) {
  Mesh out;
  const draco::PointAttribute* position = in.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (!position) return out;
  out.positions.resize(3 * static_cast<std::size_t>(in.num_points()));
  for (draco::PointIndex p(0); p < in.num_points(); ++p)
    position->GetMappedValue(p, &out.positions[3 * static_cast<std::size_t>(p.value())]);
  out.indices.reserve(3 * static_cast<std::size_t>(in.num_faces()));
  for (draco::FaceIndex f(0); f < in.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) out.indices.push_back(in.face(f)[k].value());
  return weld_identical_positions(out);
}

}  // namespace lightvol::detail
