#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <draco/attributes/attribute_quantization_transform.h>
#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>

#include <lightvol/core/detail/isolated.h>
#include <lightvol/core/limits.h>
#include <lightvol/io/detail/draco_mesh.h>

namespace lightvol::detail {
namespace {

// A third-party message on one line: runs of line breaks become "; ".
std::string one_line(const std::string& message) {
  std::string out;
  bool broken = false;
  for (const char c : message) {
    if (c == '\n' || c == '\r') {
      broken = !out.empty();
      continue;
    }
    if (broken) out += "; ";
    broken = false;
    out += c;
  }
  return out;
}

// Draco's decoding, unwelded: run in a child process (decode_draco), since Draco's decoders are not
// hardened against hostile data.
Result<DracoMesh> decode_in_this_process(std::string_view bytes,
                                         std::optional<std::uint32_t> position_id) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  // Quantized positions come back as Draco's integers with the grid beside them, so that the grid's
  // spacing is known; they are dequantized below with Draco's own arithmetic.
  decoder.SetSkipAttributeTransform(draco::GeometryAttribute::POSITION);
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok())
    return Error{"not a Draco mesh: " + one_line(decoded.status().error_msg_string())};
  const draco::Mesh& in = *decoded.value();
  const draco::PointAttribute* position =
      position_id ? in.GetAttributeByUniqueId(*position_id)
                  : in.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (!position)
    return Error{position_id ? "no attribute has the POSITION id " + std::to_string(*position_id)
                             : std::string("the mesh has no POSITION attribute")};
  // A decoded file can hold any number of components of any type, and map points to values
  // beyond the attribute (fuzz finding: a 7-component POSITION was copied into 3 floats).
  if (position->num_components() != 3)
    return Error{"POSITION has " + std::to_string(position->num_components()) +
                 " components, not 3"};
  // Numbers only (fuzz finding: a bool POSITION holding other bytes than 0 and 1 was read as bool).
  switch (position->data_type()) {
    case draco::DT_FLOAT32:
    case draco::DT_FLOAT64:
    case draco::DT_INT8:
    case draco::DT_UINT8:
    case draco::DT_INT16:
    case draco::DT_UINT16:
    case draco::DT_INT32:
    case draco::DT_UINT32:
      break;
    default:
      return Error{"POSITION is not of a number type"};
  }
  // Draco's dequantization (AttributeQuantizationTransform): value = float(q) * (range / max) +
  // min, in float, with max = 2^bits − 1.
  draco::AttributeQuantizationTransform quantization;
  const bool quantized = position->GetAttributeTransformData() != nullptr;
  float delta = 0;
  if (quantized) {
    if (!quantization.InitFromAttribute(*position) || quantization.quantization_bits() < 1 ||
        quantization.quantization_bits() > 30 || quantization.min_values().size() != 3 ||
        !std::isfinite(quantization.range()) || quantization.range() < 0)
      return Error{"POSITION has an invalid quantization"};
    delta = quantization.range() / static_cast<float>((1u << quantization.quantization_bits()) - 1);
  }

  DracoMesh out;
  out.step = delta;
  std::vector<float>& positions = out.mesh.positions;
  positions.resize(3 * static_cast<std::size_t>(in.num_points()));
  for (draco::PointIndex p(0); p < in.num_points(); ++p) {
    const draco::AttributeValueIndex value = position->mapped_index(p);
    float* xyz = &positions[3 * static_cast<std::size_t>(p.value())];
    bool ok = value.value() < position->size();
    if (ok && quantized) {
      std::int32_t q[3];
      ok = position->ConvertValue<std::int32_t, 3>(value, q);
      for (int c = 0; c < 3; ++c)
        xyz[c] = static_cast<float>(q[c]) * delta + quantization.min_value(c);
    } else if (ok) {
      ok = position->ConvertValue<float, 3>(value, xyz);
    }
    if (!ok) return Error{"point " + std::to_string(p.value()) + " has no POSITION value"};
  }
  out.mesh.indices.reserve(3 * static_cast<std::size_t>(in.num_faces()));
  for (draco::FaceIndex f(0); f < in.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = in.face(f)[k].value();
      if (v >= in.num_points())
        return Error{"face " + std::to_string(f.value()) + " names point " + std::to_string(v) +
                     ", but there are " + std::to_string(in.num_points())};
      out.mesh.indices.push_back(v);
    }
  }
  return out;
}

// The child's answer: a verdict, then the step and the mesh.
void send(const Result<DracoMesh>& decoded, ChildOutput& out) {
  if (!decoded) return out.refuse(decoded.error());
  out.accept();
  out.write_value(decoded->step);
  out.write_mesh(decoded->mesh);
}

// Reads the child's answer, trusting nothing but what it can check: counts within the budget and
// whole triangles, every index naming a point.
Status receive(ChildInput& in, Result<DracoMesh>* result) {
  const Error broken{"Draco's decoder broke off its answer"};
  if (Status answer; !in.read_go_on(result, broken, &answer)) return answer;
  DracoMesh out;
  if (!in.read_value(&out.step) || !std::isfinite(out.step) || out.step < 0) return broken;
  Status refused;
  if (!in.read_mesh(&out.mesh, "the Draco data", &refused))
    return refused ? Status{broken} : refused;
  *result = std::move(out);
  return {};
}

}  // namespace

std::vector<Result<DracoMesh>> decode_draco_all(const std::vector<DracoRequest>& requests) {
  // One child process decodes them all, in order: a crash, hang or runaway allocation in Draco
  // stays there. Its limits are far above what real data needs (tests/bench/draco_bench): an
  // 8.4 M-triangle volume is 4.2 MiB and decodes in 1.3 s, in 540 MiB, a flat one of as many
  // triangles is 2.2 MiB in as much memory; so 5 s of processor time and 10 s per MiB of data,
  // four times that in wall-clock time on a loaded machine, and 256 MiB and 4096 bytes per byte
  // of data, this within the memory budget (fuzzing found data of 52 bytes for which Draco
  // allocates 2.8 GB).
  std::size_t bytes = 0;
  for (const DracoRequest& r : requests) bytes += r.bytes.size();
  IsolationLimits limits;
  limits.cpu_seconds = 5 + 10.0 * static_cast<double>(bytes) / (1 << 20);
  limits.wall_seconds = 10 + 4 * limits.cpu_seconds;
  const std::uint64_t per_byte = 4096 * static_cast<std::uint64_t>(bytes);
  limits.memory = (std::uint64_t{256} << 20) + std::min(per_byte, memory_budget());
  if (per_byte <= memory_budget())
    limits.memory_advice =
        "no Draco mesh of " + std::to_string(bytes) + " bytes needs that much: the data is corrupt";
  std::vector<Result<DracoMesh>> decoded;
  decoded.reserve(requests.size());
  const Status run = run_isolated(
      "Draco's decoder", limits,
      [&](ChildOutput& out) {
        for (const DracoRequest& r : requests)
          send(decode_in_this_process(r.bytes, r.position_id), out);
      },
      [&](ChildInput& in) -> Status {
        while (decoded.size() < requests.size()) {
          Result<DracoMesh> one = Error{""};
          if (Status s = receive(in, &one); !s) return s;
          decoded.push_back(std::move(one));
        }
        return {};
      });
  // The request being decoded when the child failed gets its error (the last one if the child
  // failed after answering them all); any after it were not reached.
  if (!run && decoded.size() == requests.size() && !decoded.empty()) decoded.back() = run.error();
  if (!run && decoded.size() < requests.size()) decoded.emplace_back(run.error());
  while (decoded.size() < requests.size())
    decoded.emplace_back(Error{"not decoded: Draco's decoder failed on earlier data"});
  for (Result<DracoMesh>& d : decoded)
    if (d) d->mesh = weld_identical_positions(d->mesh);
  return decoded;
}

Result<DracoMesh> decode_draco(std::string_view bytes, std::optional<std::uint32_t> position_id) {
  return std::move(decode_draco_all({{bytes, position_id}})[0]);
}

Result<DracoMesh> decode_draco_unisolated(std::string_view bytes,
                                          std::optional<std::uint32_t> position_id) {
  Result<DracoMesh> decoded = decode_in_this_process(bytes, position_id);
  if (!decoded) return decoded;
  decoded->mesh = weld_identical_positions(decoded->mesh);
  return decoded;
}

}  // namespace lightvol::detail
