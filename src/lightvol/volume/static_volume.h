// The static light volume (docs/design.md §3): one vertex per texel, closed to the light.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/mesh_stream.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>

namespace lightvol {

struct VolumeOptions {
  Space space = Space::world;              // frame of the output: world, or the light's eye space
  std::string light_source = "the light";  // names the light's file in float32 refusals
};

// Triangle and vertex counts of the static volume of a W×H map, in closed form.
// spot: W·H + 1 vertices, 2(W−1)(H−1) + B triangles, B = 2(W−1) + 2(H−1) border edges.
// directional: W·H + B + 1 vertices, 2(W−1)(H−1) + 3B triangles (walls 2B, cap B).
struct VolumeCounts {
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
};
VolumeCounts static_volume_counts(LightType type, int width, int height);

// The texel ring around a W×H grid: vertex indices (row-major, row·W + col) of the border, in the
// direction the grid's boundary edges run when `standard` winding is used: top row left to right,
// right column down, bottom row right to left, left column up. Reversed otherwise.
std::vector<std::uint32_t> border_loop(int width, int height, bool standard);

// The triangles of build_static_volume's volume of a W×H map of `light` (spot or directional), as
// it numbers them: they depend on the light only through its type and winding, never on the
// depths. For drawing a volume whose vertices are made elsewhere (the GPU's live volume,
// render/live_volume.h) with build's triangles.
std::vector<std::uint32_t> static_volume_indices(const Light& light, int width, int height);

// Builds the static volume of a spot or directional light from its depth image:
// grid vertices at each texel centre's ray and depth (Unprojector), triangulated quad by quad;
// spot: a fan from the border to the light position; directional: the border extruded to the
// near plane and capped by a fan around the cap's centre. Closed, edge-manifold, outward.
// `source` names the depth image in errors (a radial depth no parallel ray reaches); a volume
// float32 cannot hold is refused with check_representable's Error (volume/float32_guard.h),
// naming options.light_source.
// `storage` (optional): reserve_static_volume's buffers, filled when they have room for this
// volume (else dropped): the same mesh, without the page faults.
Result<Mesh> build_static_volume(const Light& light, const DepthImage& depth,
                                 const VolumeOptions& options, const std::string& source,
                                 Mesh storage = {});

// Room for the static volume of a W×H map of a spot or directional light (`type`): a mesh with no
// vertices and no triangles whose buffers are reserved for them and already mapped
// (MADV_POPULATE_WRITE, in this thread only: the kernel zeroes fresh pages as it maps them, which
// on a virtual machine is the slowest part of a large build). Made on a thread of its own while
// the map is read, then handed to build_static_volume (pipeline/build_file.cpp).
Mesh reserve_static_volume(LightType type, int width, int height);

// The static volume of build_static_volume as a stream (core/mesh_stream.h): produced in blocks of
// rows and never held whole (memory: a few rows and the border), with the same vertices and
// triangles in the same order, so a file written from it has the same bytes. positions() makes
// the rows twice (the float32 guard's faces need the largest coordinate first) and fails as
// build_static_volume does (a radial depth no ray reaches) and as check_representable does, with
// the same message (`light_source` names the light): before any position is handed on when the
// vertices alone decide, else at its end, before any triangle. After it, bounds() and volume() are
// bounding_box and signed_volume of the mesh. `light` and `depth` must outlive the stream.
class StaticVolumeStream : public MeshStream {
 public:
  StaticVolumeStream(const Light& light, const DepthImage& depth, const VolumeOptions& options,
                     std::string source, std::string light_source);
  ~StaticVolumeStream() override;
  std::uint64_t num_vertices() const override;
  std::uint64_t num_triangles() const override;
  Status positions(const PositionSink& sink) override;
  Status triangles(const TriangleSink& sink) override;
  Bounds bounds() const { return bounds_; }
  double volume() const { return volume_; }

 private:
  struct State;
  std::unique_ptr<State> state_;
  Bounds bounds_;
  double volume_ = 0;
};

}  // namespace lightvol
