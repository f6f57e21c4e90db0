#include <lightvol/io/draco_mesh.h>

#include <string>

#include <lightvol/check/topology.h>

namespace lightvol::detail {

Result<Mesh> from_draco(const draco::Mesh& in) {
  Mesh out;
  const draco::PointAttribute* position = in.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (!position) return out;
  // A decoded file can hold any number of components of any type, and map points to values
  // beyond the attribute (fuzz finding: a 7-component POSITION was copied into 3 floats).
  if (position->num_components() != 3)
    return Error{"POSITION has " + std::to_string(position->num_components()) + " components, not 3"};
  // Numbers only (fuzz finding: a bool POSITION holding other bytes than 0 and 1 was read as bool).
  switch (position->data_type()) {
    case draco::DT_FLOAT32: case draco::DT_FLOAT64: case draco::DT_INT8: case draco::DT_UINT8:
    case draco::DT_INT16: case draco::DT_UINT16: case draco::DT_INT32: case draco::DT_UINT32: break;
    default: return Error{"POSITION is not of a number type"};
  }
  out.positions.resize(3 * static_cast<std::size_t>(in.num_points()));
  for (draco::PointIndex p(0); p < in.num_points(); ++p) {
    const draco::AttributeValueIndex value = position->mapped_index(p);
    if (value.value() >= position->size() ||
        !position->ConvertValue<float, 3>(value, &out.positions[3 * static_cast<std::size_t>(p.value())]))
      return Error{"point " + std::to_string(p.value()) + " has no POSITION value"};
  }
  out.indices.reserve(3 * static_cast<std::size_t>(in.num_faces()));
  for (draco::FaceIndex f(0); f < in.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = in.face(f)[k].value();
      if (v >= in.num_points())
        return Error{"face " + std::to_string(f.value()) + " names point " + std::to_string(v) + ", but there are " +
                     std::to_string(in.num_points())};
      out.indices.push_back(v);
    }
  }
  return weld_identical_positions(out);
}

}  // namespace lightvol::detail
