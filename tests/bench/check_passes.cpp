// The linear checks' passes one at a time on the static volume of the synthetic spot map (N², 4096
// by default), on one thread (the processor time of each pass) or on all (wall time): the vertex
// pass, the edge pass, the face pass with the light, the float32 guard of the build, and the whole
// check_volume_linear. The face pass's sums are printed in hexadecimal, to compare versions bit for
// bit. Usage: check_passes [N] [THREADS] [REPEATS]
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>

#include <tbb/global_control.h>

#include <lightvol/check/check.h>
#include <lightvol/check/detail/linear_checks.h>
#include <lightvol/volume/float32_guard.h>
#include <lightvol/volume/static_volume.h>

#include "synthetic_scene.h"

namespace {

double now(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The least time of `repeats` runs of `f`: processor time of this thread with one thread, wall
// time otherwise.
double best(int repeats, bool one_thread, const std::function<void()>& f) {
  const clockid_t clock = one_thread ? CLOCK_THREAD_CPUTIME_ID : CLOCK_MONOTONIC;
  double least = 1e30;
  for (int k = 0; k < repeats; ++k) {
    const double t0 = now(clock);
    f();
    least = std::min(least, now(clock) - t0);
  }
  return least;
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 4096;
  const int threads = argc > 2 ? std::atoi(argv[2]) : 1;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 3;
  const lightvol::Light light = *lightvol::parse_light(
      R"({"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
          "fov_y_deg": 60, "near": 1, "far": 20})",
      "bench");
  const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(n, n);
  const lightvol::Mesh mesh = *lightvol::build_static_volume(light, depth, {}, "bench");
  const tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
  const bool one = threads == 1;
  using namespace lightvol::detail;  // NOLINT(google-build-using-namespace): the passes
  lightvol::detail::VertexScan scan;
  std::printf("%d² (%zu triangles), %d thread(s), least of %d, %s seconds\n", n,
              mesh.num_triangles(), threads, repeats, one ? "processor" : "wall");
  std::printf("vertices  %.3f\n",
              best(repeats, one, [&] { scan = scan_vertices(mesh, &light, 0); }));
  std::printf("edges     %.3f\n", best(repeats, one, [&] { (void)edge_checks(mesh, 5); }));
  const LightView view = point_view(mesh, light, scan, 0);
  FaceSums sums;
  std::printf("faces     %.3f\n", best(repeats, one, [&] { sums = face_pass(mesh, view); }));
  std::printf("guard     %.3f\n", best(repeats, one, [&] {
                (void)lightvol::check_representable(mesh, light, lightvol::Space::world, "bench");
              }));
  lightvol::CheckReport report;
  std::printf("check     %.3f\n",
              best(repeats, one, [&] { report = lightvol::check_volume_linear(mesh, &light); }));
  std::printf("sums det %a positive %a negative %a zeroed %a wrong %llu degenerate %llu\n",
              sums.det, sums.light.positive, sums.light.negative, sums.light.zeroed,
              static_cast<unsigned long long>(sums.light.wrong),
              static_cast<unsigned long long>(sums.degenerate));
  std::printf("report valid %d light_sum %a volume %a\n", report.valid() ? 1 : 0, report.light_sum,
              report.volume);
  return 0;
}
