// An OpenMesh exporter over the flat Mesh buffers, so OpenMesh's writers stream our mesh without
// building a half-edge structure first. Internal to src/export.
#pragma once

#include <OpenMesh/Core/IO/exporter/BaseExporter.hh>

#include <lightvol/core/mesh.h>

namespace lightvol::detail {

class FlatExporter final : public OpenMesh::IO::BaseExporter {
 public:
  explicit FlatExporter(const Mesh& mesh) : mesh_(mesh) {}

  using Vec3f = OpenMesh::Vec3f;
  using Vec3d = OpenMesh::Vec3d;
  using VH = OpenMesh::VertexHandle;
  using FH = OpenMesh::FaceHandle;
  using EH = OpenMesh::EdgeHandle;
  using HH = OpenMesh::HalfedgeHandle;
  using Status = OpenMesh::Attributes::StatusInfo;

  Vec3f point(VH v) const override {
    const float* p = &mesh_.positions[3 * static_cast<std::size_t>(v.idx())];
    return {p[0], p[1], p[2]};
  }
  Vec3d pointd(VH v) const override {
    const Vec3f p = point(v);
    return {p[0], p[1], p[2]};
  }
  bool is_point_double() const override { return false; }
  Vec3f normal(VH) const override { return {0, 0, 0}; }
  Vec3d normald(VH) const override { return {0, 0, 0}; }
  bool is_normal_double() const override { return false; }
  OpenMesh::Vec3uc color(VH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4uc colorA(VH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3ui colori(VH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4ui colorAi(VH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3f colorf(VH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4f colorAf(VH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec2f texcoord(VH) const override { return {0, 0}; }
  OpenMesh::Vec2f texcoord(HH) const override { return {0, 0}; }
  Status status(VH) const override { return {}; }

  unsigned int get_vhandles(FH f, std::vector<VH>& out) const override {
    const std::size_t t = static_cast<std::size_t>(f.idx());
    out.resize(3);
    for (int k = 0; k < 3; ++k) out[k] = VH(static_cast<int>(mesh_.indices[3 * t + k]));
    return 3;
  }
  HH getHeh(FH, VH) const override { return HH(); }
  unsigned int get_face_texcoords(std::vector<OpenMesh::Vec2f>&) const override { return 0; }
  Vec3f normal(FH f) const override {
    const auto [a, b, c] = mesh_.triangle(static_cast<std::size_t>(f.idx()));
    const Vec3f pa = point(VH(static_cast<int>(a))), pb = point(VH(static_cast<int>(b))),
                pc = point(VH(static_cast<int>(c)));
    Vec3f n = (pb - pa) % (pc - pa);
    const float len = n.norm();
    return len > 0 ? n / len : n;
  }
  Vec3d normald(FH f) const override {
    const Vec3f n = normal(f);
    return {n[0], n[1], n[2]};
  }
  OpenMesh::Vec3uc color(FH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4uc colorA(FH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3ui colori(FH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4ui colorAi(FH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3f colorf(FH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4f colorAf(FH) const override { return {0, 0, 0, 0}; }
  Status status(FH) const override { return {}; }

  OpenMesh::Vec3uc color(EH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4uc colorA(EH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3ui colori(EH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4ui colorAi(EH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3f colorf(EH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4f colorAf(EH) const override { return {0, 0, 0, 0}; }
  Status status(EH) const override { return {}; }

  int get_halfedge_id(VH) override { return -1; }
  int get_halfedge_id(FH) override { return -1; }
  int get_next_halfedge_id(HH) override { return -1; }
  int get_to_vertex_id(HH) override { return -1; }
  int get_face_id(HH) override { return -1; }
  Status status(HH) const override { return {}; }

  size_t n_vertices() const override { return mesh_.num_vertices(); }
  size_t n_faces() const override { return mesh_.num_triangles(); }
  size_t n_edges() const override { return 0; }
  bool is_triangle_mesh() const override { return true; }

 private:
  const Mesh& mesh_;
};

}  // namespace lightvol::detail
