// A mesh produced in order instead of held whole: its counts known up front, its positions and
// then its triangles handed block by block to a consumer (export's write_mesh_stream writes them
// straight to a file), so that memory does not grow with the mesh.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol {

class MeshStream {
 public:
  // A block of `count` vertices (3·count floats, x y z) or triangles (3·count indices); returning
  // false stops the stream (the consumer failed and knows why).
  using PositionSink = std::function<bool(const float* xyz, std::size_t count)>;
  using TriangleSink = std::function<bool(const std::uint32_t* abc, std::size_t count)>;

  virtual ~MeshStream() = default;
  virtual std::uint64_t num_vertices() const = 0;
  virtual std::uint64_t num_triangles() const = 0;
  // Every position in vertex order, then (a second call) every triangle in order. An Error is the
  // producer's own (bad input found while producing): the consumer must then discard what it has.
  virtual Status positions(const PositionSink& sink) = 0;
  virtual Status triangles(const TriangleSink& sink) = 0;
};

// A held Mesh as a stream, in blocks of 2^16 elements.
class MeshBufferStream : public MeshStream {
 public:
  explicit MeshBufferStream(const Mesh& mesh) : mesh_(mesh) {}
  std::uint64_t num_vertices() const override { return mesh_.num_vertices(); }
  std::uint64_t num_triangles() const override { return mesh_.num_triangles(); }
  Status positions(const PositionSink& sink) override;
  Status triangles(const TriangleSink& sink) override;

 private:
  const Mesh& mesh_;
};

// signed_volume over triangles that arrive in order, block by block: the same sums in the same
// order as signed_volume(mesh), so the same double, bit for bit (signed_volume uses it).
class SignedVolumeSum {
 public:
  explicit SignedVolumeSum(std::size_t triangles);
  // Adds triangles [first, first + count), the next ones in order; corner(t, k) points to the x y
  // z floats of corner k of triangle t. Parallel over the leaves of the sum the block touches.
  template <class Corner>
  void add(std::size_t first, std::size_t count, const Corner& corner) {
    add_runs(first, count, [&](std::size_t t0, std::size_t t1, double acc) {
      for (std::size_t t = t0; t != t1; ++t)
        acc += volume_det(corner(t, 0), corner(t, 1), corner(t, 2));
      return acc;
    });
  }
  // The same, for callers that walk their triangles faster than one lookup each: run(t0, t1, acc)
  // returns acc plus volume_det of triangles [t0, t1), added in order.
  template <class Run>
  void add_runs(std::size_t first, std::size_t count, const Run& run) {
    for_each_leaf(first, first + count, [&](std::size_t leaf, std::size_t t0, std::size_t t1) {
      leaf_sum_[leaf] = run(t0, t1, leaf_sum_[leaf]);
    });
  }
  double volume() const;

 private:
  // Calls f(leaf, t0, t1) for each leaf's part [t0, t1) of [begin, end), in parallel.
  void for_each_leaf(std::size_t begin, std::size_t end,
                     const std::function<void(std::size_t, std::size_t, std::size_t)>& f);
  void split(std::size_t begin, std::size_t end);
  double fold(std::size_t begin, std::size_t end, std::size_t* leaf) const;
  std::size_t triangles_;
  std::vector<std::size_t> leaf_begin_;  // the leaves' first triangles, as the reduction splits
  std::vector<double> leaf_sum_;
};

}  // namespace lightvol
