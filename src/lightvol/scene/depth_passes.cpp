#include <utility>

#include <lightvol/scene/bvh.h>
#include <lightvol/scene/depth_passes.h>
#include <lightvol/scene/raycast.h>

namespace lightvol {
namespace {

class CpuDepthPasses final : public DepthPasses {
 public:
  explicit CpuDepthPasses(const Mesh& scene) : scene_(scene) {}

  std::string method() const override { return "CPU ray casting"; }

  Result<std::vector<float>> window_depth(const Light& view, int width, int height, int face,
                                          double* gpu_seconds) override {
    if (!bvh_) bvh_ = std::make_unique<Bvh>(scene_);
    const std::vector<double> d = raycast_window_depth(*bvh_, view, width, height, face);
    if (gpu_seconds) *gpu_seconds = 0;
    return std::vector<float>(d.begin(), d.end());
  }

 private:
  const Mesh& scene_;
  std::unique_ptr<Bvh> bvh_;
};

}  // namespace

std::unique_ptr<DepthPasses> cpu_depth_passes(const Mesh& scene) {
  return std::make_unique<CpuDepthPasses>(scene);
}

double RenderedPasses::hit_fraction() const {
  std::size_t hit = 0, total = 0;
  for (const std::vector<float>& pass : window) {
    for (const float d : pass) hit += d < 1.0f ? 1 : 0;
    total += pass.size();
  }
  return total == 0 ? 0.0 : static_cast<double>(hit) / static_cast<double>(total);
}

Result<RenderedPasses> render_passes(DepthPasses& passes, const Light& view, MapSize size) {
  RenderedPasses out;
  const int count = pass_count(view);
  for (int face = 0; face < count; ++face) {
    double seconds = 0;
    Result<std::vector<float>> d =
        passes.window_depth(view, size.width, size.height, face, &seconds);
    if (!d) return d.error();
    out.window.push_back(std::move(*d));
    out.gpu_seconds += seconds;
  }
  if (view.type == LightType::omni) {
    out.maps.omni = true;
    for (int face = 0; face < kOmniFaces; ++face)
      out.maps.cube.faces[static_cast<std::size_t>(face)] =
          encode_depth(view, size.width, size.height, out.window[static_cast<std::size_t>(face)]);
  } else {
    out.maps.image = encode_depth(view, size.width, size.height, out.window[0]);
  }
  return out;
}

}  // namespace lightvol
