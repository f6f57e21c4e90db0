// Decoding Draco meshes into the flat Mesh, shared by the reader (DRC files, Draco-compressed GLB
// primitives) and the exporters (which decode what they encoded, to verify it). Internal to the
// library.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol::detail {

// A decoded Draco mesh and the spacing of the grid its positions were quantized to (0 when they
// were stored unquantized): each position lies within half a step of what was encoded.
struct DracoMesh {
  Mesh mesh;
  double step = 0;
};

// Decodes `bytes` as a Draco mesh: the positions (dequantized exactly as Draco's decoder does) of
// the attribute with unique id `position_id` (glTF names it) or else of the POSITION attribute,
// and the faces, with bit-identical positions welded (Draco may split points by attribute). Data
// Draco cannot decode, a missing position attribute or one of other than 3 numeric components, a
// point mapped past its values or a face naming a missing point is an Error whose message names
// no file (the caller prefixes it).
// Draco runs in a child process (core/isolated.h): a crash inside Draco, more than 5 s + 10 s per
// MiB of `bytes` of processor time, or an allocation beyond the memory budget is an Error too.
Result<DracoMesh> decode_draco(std::string_view bytes,
                               std::optional<std::uint32_t> position_id = {});

// Several decodings in one child process (a GLB's compressed primitives), each as decode_draco,
// in order. If the child fails, the data it was decoding gets that Error, the data after it an
// Error saying it was not reached.
struct DracoRequest {
  std::string_view bytes;
  std::optional<std::uint32_t> position_id;
};
std::vector<Result<DracoMesh>> decode_draco_all(const std::vector<DracoRequest>& requests);

// The same decoding in this process, trusting Draco: only for measuring what the isolation costs
// (tests/bench/draco_bench). Readers use decode_draco.
Result<DracoMesh> decode_draco_unisolated(std::string_view bytes,
                                          std::optional<std::uint32_t> position_id = {});

}  // namespace lightvol::detail
